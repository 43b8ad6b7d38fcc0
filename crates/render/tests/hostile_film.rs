//! Films as a hostile user (or a failing disk) hands them over: every
//! truncation, single-bit flips across the whole file, and headers crafted
//! with a valid checksum but absurd counts. Each must be an error — never a
//! panic, an abort (an attempt to allocate what the header claims) or a
//! film silently accepted with other contents.

use render::film::{BadSample, Film, MAX_PIXELS, MAX_SIDE, ResumeError};
use render::inputs::InputFile;

/// A small film with every section populated.
fn sample_film() -> Film {
    let mut f = Film::new(5, 3, 0x1234_5678_9abc_def0, 42, 0.5)
        .unwrap()
        .with_inputs(vec![
            InputFile {
                name: "scene.toml".into(),
                len: 812,
                hash: 0x0102_0304_0506_0708,
            },
            InputFile {
                name: "materials/fit.toml".into(),
                len: 90_210,
                hash: 0xfeed_beef_cafe_f00d,
            },
        ]);
    f.add_range(0..64).unwrap();
    f.add_range(128..256).unwrap();
    let mut p = f.into_parts();
    for (i, s) in p.sums.iter_mut().enumerate() {
        // X and Z may dip below zero (a narrow band's exactly integrated XYZ,
        // a signed sky); Y may not.
        *s = [-(i as i128), i as i128 * 7, i as i128 * 1_000_003];
    }
    p.dropped.record(BadSample::NonFinite, 2, 1, 17);
    p.dropped.record(BadSample::Negative, 4, 2, 130);
    Film::from_parts(p).unwrap()
}

/// Header offsets of format 2 (see film.rs).
const OFF_WIDTH: usize = 12;
const OFF_HEIGHT: usize = 16;
const OFF_INPUT_COUNT: usize = 12 + 8 + 24 + 16 + 16;

/// Replaces the trailing CRC so that a crafted body passes the checksum.
fn reseal(mut body: Vec<u8>) -> Vec<u8> {
    body.truncate(body.len() - 4);
    let crc = crc32(&body);
    body.extend_from_slice(&crc.to_le_bytes());
    body
}

/// CRC-32 (IEEE), written out here so the test does not trust the
/// implementation it checks.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xedb8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

#[test]
fn round_trip_is_exact_and_checksummed_with_crc32() {
    let f = sample_film();
    let bytes = f.to_bytes();
    assert_eq!(Film::from_bytes(&bytes).unwrap(), f);
    let n = bytes.len();
    let stored = u32::from_le_bytes(bytes[n - 4..].try_into().unwrap());
    assert_eq!(stored, crc32(&bytes[..n - 4]));
}

#[test]
fn every_truncation_is_an_error() {
    let bytes = sample_film().to_bytes();
    for len in 0..bytes.len() {
        let r = Film::from_bytes(&bytes[..len]);
        assert!(
            r.is_err(),
            "a film cut to {len} of {} bytes was accepted",
            bytes.len()
        );
    }
    // And trailing garbage.
    let mut longer = bytes.clone();
    longer.push(0);
    assert!(Film::from_bytes(&longer).is_err());
}

#[test]
fn every_single_bit_flip_is_detected() {
    let bytes = sample_film().to_bytes();
    let bits = bytes.len() * 8;
    assert!(bits >= 1000, "{bits} bit positions");
    for bit in 0..bits {
        let mut b = bytes.clone();
        b[bit / 8] ^= 1 << (bit % 8);
        match Film::from_bytes(&b) {
            Ok(_) => panic!("flipping bit {bit} (byte {}) went unnoticed", bit / 8),
            Err(e) => {
                // Past the magic, the checksum catches it and says so.
                if bit >= 96 {
                    assert!(e.contains("checksum"), "bit {bit}: {e}");
                }
            }
        }
    }
}

#[test]
fn random_multi_byte_damage_is_detected() {
    let bytes = sample_film().to_bytes();
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    for _ in 0..5000 {
        let mut b = bytes.clone();
        let k = 1 + (next() % 8) as usize;
        for _ in 0..k {
            let i = (next() % b.len() as u64) as usize;
            b[i] = next() as u8;
        }
        if b != bytes {
            assert!(Film::from_bytes(&b).is_err());
        }
    }
}

#[test]
fn crafted_headers_with_valid_checksums_are_refused_without_allocating() {
    let good = sample_film().to_bytes();
    let put32 =
        |b: &mut Vec<u8>, off: usize, v: u32| b[off..off + 4].copy_from_slice(&v.to_le_bytes());
    let mut cases: Vec<(&str, Vec<u8>)> = Vec::new();

    // 48-byte style: the largest dimensions a u32 can claim (the 206 GB case).
    for (w, h) in [
        (u32::MAX, u32::MAX),
        (MAX_SIDE, MAX_SIDE),
        (MAX_SIDE + 1, 1),
        (0, 3),
        (5, 0),
        (1 << 14, 1 << 14),
    ] {
        let mut b = good.clone();
        put32(&mut b, OFF_WIDTH, w);
        put32(&mut b, OFF_HEIGHT, h);
        cases.push(("dimensions", reseal(b)));
    }
    // A bare header claiming a big film, with no body at all.
    let mut bare = good[..OFF_INPUT_COUNT + 4].to_vec();
    put32(&mut bare, OFF_WIDTH, 30_000);
    put32(&mut bare, OFF_HEIGHT, 30_000);
    bare.extend_from_slice(&[0; 4]); // no ranges
    bare.extend_from_slice(&[0; 4]); // room for the CRC
    cases.push(("bare header", reseal(bare)));
    // Input and range counts far beyond the file.
    for n in [u32::MAX, 1 << 20, 3] {
        let mut b = good.clone();
        put32(&mut b, OFF_INPUT_COUNT, n);
        cases.push(("input count", reseal(b)));
    }
    // The first input's name length.
    for n in [u32::MAX, 4097, 200] {
        let mut b = good.clone();
        put32(&mut b, OFF_INPUT_COUNT + 4, n);
        cases.push(("name length", reseal(b)));
    }
    // Range count: locate it after the two inputs.
    let off_ranges = OFF_INPUT_COUNT + 4 + (4 + 10 + 16) + (4 + 18 + 16);
    assert_eq!(
        u32::from_le_bytes(good[off_ranges..off_ranges + 4].try_into().unwrap()),
        2
    );
    for n in [u32::MAX, 1 << 28, 3, 0] {
        let mut b = good.clone();
        put32(&mut b, off_ranges, n);
        cases.push(("range count", reseal(b)));
    }
    // Ranges that overlap, repeat, run backwards or are empty.
    let range_at = |b: &mut Vec<u8>, i: usize, a: u64, e: u64| {
        let o = off_ranges + 4 + 16 * i;
        b[o..o + 8].copy_from_slice(&a.to_le_bytes());
        b[o + 8..o + 16].copy_from_slice(&e.to_le_bytes());
    };
    for (a0, e0, a1, e1) in [
        (0, 64, 32, 96),
        (0, 64, 0, 64),
        (128, 256, 0, 64),
        (64, 0, 128, 256),
        (0, 0, 128, 256),
        (0, 64, 64, 128),
    ] {
        let mut b = good.clone();
        range_at(&mut b, 0, a0, e0);
        range_at(&mut b, 1, a1, e1);
        cases.push(("ranges", reseal(b)));
    }
    // Non-finite exposure, a dropped location outside the image, counts
    // without a location.
    let mut b = good.clone();
    b[36..44].copy_from_slice(&f64::NAN.to_le_bytes());
    cases.push(("exposure", reseal(b)));
    let mut b = good.clone();
    put32(&mut b, 68, 99);
    cases.push(("dropped x", reseal(b)));
    let mut b = good.clone();
    b[44..60].copy_from_slice(&[0; 16]);
    cases.push(("dropped counts", reseal(b)));
    // Fields a render cannot produce, each with a valid checksum: an exposure past
    // the scene's limit (every EXR value inf), a range to 2⁶⁴ − 1, no range at all,
    // a negative luminance sum, a sum no 192 samples can reach, more dropped
    // samples than were taken.
    for stops in [1000.0f64, -61.0, f64::INFINITY] {
        let mut b = good.clone();
        b[36..44].copy_from_slice(&stops.to_le_bytes());
        cases.push(("exposure", reseal(b)));
    }
    let mut b = good.clone();
    range_at(&mut b, 1, 128, u64::MAX);
    cases.push(("range end", reseal(b)));
    let mut b = good[..off_ranges].to_vec();
    b.extend_from_slice(&0u32.to_le_bytes());
    b.extend_from_slice(&good[off_ranges + 4 + 32..]);
    cases.push(("no range", reseal(b)));
    let off_sums = off_ranges + 4 + 32;
    let sum_at = |b: &mut Vec<u8>, px: usize, k: usize, v: i128| {
        let o = off_sums + 48 * px + 16 * k;
        b[o..o + 16].copy_from_slice(&v.to_le_bytes());
    };
    for (k, v) in [(1, -1), (1, i128::MAX), (0, i128::MIN), (2, i128::MAX / 2)] {
        let mut b = good.clone();
        sum_at(&mut b, 7, k, v);
        cases.push(("sums", reseal(b)));
    }
    let mut b = good.clone();
    b[44..52].copy_from_slice(&(5 * 3 * 192u64).to_le_bytes());
    cases.push(("dropped count", reseal(b)));

    // Format 1 and foreign files.
    let mut v1 = good.clone();
    v1[..12].copy_from_slice(b"LUSTREFILM1\n");
    cases.push(("format 1", v1));
    cases.push(("empty", Vec::new()));
    cases.push(("png", b"\x89PNG\r\n\x1a\n0000000000000000".to_vec()));

    for (what, bytes) in &cases {
        match Film::from_bytes(bytes) {
            Ok(f) => panic!("crafted {what}: accepted as {}×{}", f.width(), f.height()),
            Err(e) => assert!(!e.is_empty(), "{what}"),
        }
    }
    assert!(MAX_PIXELS < MAX_SIDE as u64 * MAX_SIDE as u64);
}

#[test]
fn load_errors_name_the_file() {
    let dir = std::env::temp_dir().join(format!("lustre-hostile-film-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join("bad.film");
    let mut b = sample_film().to_bytes();
    b[100] ^= 4;
    std::fs::write(&p, &b).unwrap();
    let e = Film::load(&p).unwrap_err().to_string();
    assert!(e.contains("bad.film") && e.contains("checksum"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn merge_refuses_overlapping_or_duplicated_shards_and_keeps_high_indices_apart() {
    let base = sample_film();
    let shard = |r: std::ops::Range<u64>| {
        let mut f = Film::new(5, 3, base.fingerprint(), 42, 0.0).unwrap();
        f.add_range(r).unwrap();
        f
    };
    let a = shard(0..10);
    let dup = a.clone();
    assert!(a.clone().merge(&dup).unwrap_err().contains("overlaps"));
    assert!(a.clone().merge(&shard(5..20)).is_err());
    // Indices past 2³² are samples of their own (the sampler no longer
    // wraps them), so such ranges merge as disjoint.
    let high = shard((1 << 32)..(1 << 32) + 10);
    let mut m = a.clone();
    m.merge(&high).unwrap();
    assert_eq!(m.spp(), 20);
    assert!(m.merge(&high).is_err());
    // Sums that would overflow are an error, not a saturated pixel; the film is unchanged.
    let big = |r: std::ops::Range<u64>| {
        let mut p = shard(r).into_parts();
        p.sums[4] = [0, i128::MAX / 2 + 1, 0];
        Film::from_parts(p).unwrap()
    };
    // Two shards of 2²⁰ samples each, as many as those sums need.
    let (a, b) = ((1u64 << 40) - (1 << 21), (1u64 << 40) - (1 << 20));
    let mut m = big(a..b);
    let before = m.clone();
    let e = m.merge(&big(b..(1 << 40))).unwrap_err();
    assert!(e.contains("overflow"), "{e}");
    assert_eq!(m, before);
}

#[test]
fn from_parts_checks_what_a_film_file_is_checked_for() {
    let good = sample_film().into_parts();
    let refuse = |edit: &dyn Fn(&mut render::film::FilmParts), what: &str| {
        let mut p = good.clone();
        edit(&mut p);
        let e = Film::from_parts(p).unwrap_err();
        assert!(e.contains(what), "{what}: {e}");
    };
    refuse(&|p| p.sums.truncate(14), "pixel sums");
    refuse(&|p| p.ranges = vec![0..10, 5..20], "overlaps");
    refuse(&|p| p.ranges = vec![10..10, 20..30], "empty");
    refuse(&|p| p.ranges = vec![20..30, 0..10], "unsorted");
    refuse(&|p| p.exposure = f64::NAN, "exposure");
    refuse(&|p| p.width = 0, "resolution");
    refuse(&|p| p.dropped.first.as_mut().unwrap().x = 5, "outside 5×3");
    refuse(&|p| p.dropped.first = None, "disagree");
    refuse(&|p| p.exposure = 1000.0, "exposure");
    refuse(&|p| p.ranges.clear(), "no sample range");
    refuse(
        &|p| p.ranges = std::iter::once(0..u64::MAX).collect(),
        "ends beyond",
    );
    refuse(&|p| p.sums[3][1] = -5, "pixel (3, 0)");
    refuse(&|p| p.sums[14][2] = i128::MAX, "pixel (4, 2)");
    refuse(&|p| p.dropped.negative = u64::MAX, "dropped samples");
    assert_eq!(Film::from_parts(good.clone()).unwrap(), sample_film());
}

#[test]
fn resume_adopts_a_prefix_and_leaves_the_film_unchanged_otherwise() {
    let base = sample_film();
    let empty = || Film::new(5, 3, base.fingerprint(), 42, 0.0).unwrap();
    let mut done = empty();
    done.add_range(0..24).unwrap();

    let mut f = empty();
    assert_eq!(f.resume(done.clone(), 0..64), Ok(24..64));
    assert_eq!(f.ranges(), std::slice::from_ref(&(0..24)));
    // A checkpoint past the target leaves nothing to do.
    let mut f = empty();
    assert_eq!(f.resume(done.clone(), 0..16), Ok(16..16));

    let refused = |checkpoint: Film, target: std::ops::Range<u64>| {
        let mut f = empty();
        let e = f.resume(checkpoint, target).unwrap_err();
        assert_eq!(f, empty(), "film changed by a refused resume");
        e
    };
    let other_seed = Film::new(5, 3, base.fingerprint(), 7, 0.0).unwrap();
    assert!(matches!(
        refused(other_seed, 0..64),
        ResumeError::Incompatible(m) if m.contains("seed")
    ));
    let mut shard = empty();
    shard.add_range(8..24).unwrap();
    assert!(matches!(
        refused(shard, 0..64),
        ResumeError::NotAPrefix { .. }
    ));
    let mut gaps = done.clone();
    gaps.add_range(30..40).unwrap();
    let e = refused(gaps, 0..64);
    assert!(e.to_string().contains("not a prefix of 0..64"), "{e}");
}

/// `sample_film` with three spectral bands holding distinct sums (a band
/// may be negative under a signed sky).
fn banded_film() -> Film {
    let mut p = sample_film().with_bands(3).unwrap().into_parts();
    for (k, v) in p.band_sums.iter_mut().enumerate() {
        *v = (k as i128 - 20) * 1_000_000_007;
    }
    Film::from_parts(p).unwrap()
}

#[test]
fn banded_films_round_trip_and_every_damage_is_detected() {
    let f = banded_film();
    let bytes = f.to_bytes();
    assert_eq!(&bytes[..12], b"LUSTREFILM3\n");
    assert_eq!(
        bytes.len(),
        sample_film().to_bytes().len() + 4 + 15 * 3 * 16
    );
    assert_eq!(Film::from_bytes(&bytes).unwrap(), f);
    for len in 0..bytes.len() {
        assert!(Film::from_bytes(&bytes[..len]).is_err(), "cut to {len}");
    }
    for bit in 0..bytes.len() * 8 {
        let mut b = bytes.clone();
        b[bit / 8] ^= 1 << (bit % 8);
        assert!(Film::from_bytes(&b).is_err(), "bit {bit}");
    }
}

#[test]
fn crafted_band_data_with_valid_checksums_is_refused() {
    let good = banded_film().to_bytes();
    let plain = sample_film().to_bytes();
    // The band count sits where format 2's sums begin.
    let off_ranges = OFF_INPUT_COUNT + 4 + (4 + 10 + 16) + (4 + 18 + 16);
    let off_bands = off_ranges + 4 + 32;
    assert_eq!(
        u32::from_le_bytes(good[off_bands..off_bands + 4].try_into().unwrap()),
        3
    );
    let mut cases: Vec<(&str, Vec<u8>, &str)> = Vec::new();
    for (n, why) in [
        (0, "0 spectral bands"),
        (257, "257 spectral bands"),
        (u32::MAX, "spectral bands"),
        (2, "bytes of sums"),
        (4, "bytes of sums"),
    ] {
        let mut b = good.clone();
        b[off_bands..off_bands + 4].copy_from_slice(&n.to_le_bytes());
        cases.push(("band count", reseal(b), why));
    }
    // Format 3's magic on format 2's body and the other way round.
    let mut b = plain.clone();
    b[..12].copy_from_slice(b"LUSTREFILM3\n");
    cases.push(("v3 magic on v2", reseal(b), "corrupt film"));
    let mut b = good.clone();
    b[..12].copy_from_slice(b"LUSTREFILM2\n");
    cases.push(("v2 magic on v3", reseal(b), "bytes of sums"));
    // Band sums no 192 samples can produce, in the first and last pixel.
    let band_at = |b: &mut Vec<u8>, px: usize, k: usize, v: i128| {
        let o = off_bands + 4 + px * (48 + 48) + 48 + 16 * k;
        b[o..o + 16].copy_from_slice(&v.to_le_bytes());
    };
    for (px, k, v, at) in [
        (0, 0, i128::MAX, "pixel (0, 0) band 0"),
        (14, 2, i128::MIN, "pixel (4, 2) band 2"),
        (7, 1, -(i128::MAX / 2), "pixel (2, 1) band 1"),
    ] {
        let mut b = good.clone();
        band_at(&mut b, px, k, v);
        cases.push(("band sum", reseal(b), at));
    }
    for (what, bytes, why) in &cases {
        match Film::from_bytes(bytes) {
            Ok(_) => panic!("crafted {what}: accepted"),
            Err(e) => assert!(e.contains(why), "{what}: {e}"),
        }
    }
    // A 2²⁵-pixel film with 256 bands claims 128 GiB of band sums: refused
    // by count before anything is allocated.
    let mut b = good.clone();
    put_dims(&mut b, 1 << 13, 1 << 12);
    b[off_bands..off_bands + 4].copy_from_slice(&256u32.to_le_bytes());
    let e = Film::from_bytes(&reseal(b)).unwrap_err();
    assert!(e.contains("more band sums than a film holds"), "{e}");
}

fn put_dims(b: &mut [u8], w: u32, h: u32) {
    b[OFF_WIDTH..OFF_WIDTH + 4].copy_from_slice(&w.to_le_bytes());
    b[OFF_HEIGHT..OFF_HEIGHT + 4].copy_from_slice(&h.to_le_bytes());
}

#[test]
fn band_parts_are_checked_and_band_counts_must_agree() {
    let good = banded_film().into_parts();
    let refuse = |edit: &dyn Fn(&mut render::film::FilmParts), what: &str| {
        let mut p = good.clone();
        edit(&mut p);
        let e = Film::from_parts(p).unwrap_err();
        assert!(e.contains(what), "{what}: {e}");
    };
    refuse(
        &|p| p.band_sums.pop().map(drop).unwrap_or(()),
        "band sums for",
    );
    refuse(&|p| p.bands = 4, "band sums for");
    refuse(&|p| p.bands = 300, "300 spectral bands");
    refuse(&|p| p.band_sums[44] = i128::MIN, "pixel (4, 2) band 2");
    assert!(sample_film().with_bands(257).is_err());
    let e = Film::new(1 << 13, 1 << 12, 0, 0, 0.0)
        .unwrap()
        .with_bands(256)
        .unwrap_err();
    assert!(e.contains("more than a film holds"), "{e}");

    let banded = banded_film();
    let mut plain = sample_film();
    let e = plain.merge(&banded).unwrap_err();
    assert!(e.contains("3 spectral bands differ from 0"), "{e}");
    assert_eq!(
        plain,
        sample_film(),
        "a refused merge leaves the film unchanged"
    );
    let mut fresh = Film::new(5, 3, banded.fingerprint(), 42, 0.0).unwrap();
    assert!(matches!(
        fresh.resume(banded, 0..512),
        Err(ResumeError::Incompatible(m)) if m.contains("spectral bands")
    ));
}
