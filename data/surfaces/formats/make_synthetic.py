"""Write the synthetic instrument files of this folder from the public descriptions of
their formats (named in each reader's module docs in crates/fit/src/io/), for formats of
which no real sample could be obtained. Each holds the same kind of rough surface: a
random-phase power-law spectrum (seeded, so the files are reproducible byte for byte).

Run: python3 make_synthetic.py  (numpy; h5py for the DATX files; zstandard for KPK1).
SurfaceTopography's reading of the files is recorded in ../reference/statistics.json by
../reference/st_statistics.py like every other file here.
"""
import os
import struct

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def rough(nx, ny, seed, rms=1.0):
    """A (ny, nx) random-phase surface with a power-law spectrum, Sq = rms."""
    rng = np.random.default_rng(seed)
    kx = np.fft.fftfreq(nx)[None, :]
    ky = np.fft.fftfreq(ny)[:, None]
    k = np.hypot(kx, ky)
    k[0, 0] = 1.0
    amp = k ** -1.6
    amp[0, 0] = 0.0
    phase = np.exp(2j * np.pi * rng.random((ny, nx)))
    h = np.real(np.fft.ifft2(amp * phase))
    return h / h.std() * rms


# --- Olympus LEXT ---------------------------------------------------------------------

def tiff_ifd(base, entries, next_ifd=0):
    """A little-endian TIFF directory placed at byte `base`, its long values after it.
    entries: (tag, type, count, value bytes)."""
    entries = sorted(entries)
    n = len(entries)
    extra_at = base + 2 + 12 * n + 4
    head = struct.pack("<H", n)
    extra = b""
    for tag, kind, count, value in entries:
        head += struct.pack("<HHI", tag, kind, count)
        if len(value) <= 4:
            head += value.ljust(4, b"\0")
        else:
            head += struct.pack("<I", extra_at + len(extra))
            extra += value + (b"\0" if len(value) % 2 else b"")
    head += struct.pack("<I", next_ifd)
    return head + extra


def short(v):
    return (3, 1, struct.pack("<H", v))


def long(v):
    return (4, 1, struct.pack("<I", v))


def ascii(s):
    b = s.encode() + b"\0"
    return (2, len(b), b)


def lext(name, nx, ny, seed):
    # 0.125 µm × 0.13 µm pixels, calibrations of +2, -1 and -2 per mille, 1 pm per count.
    desc = (
        '<?xml version="1.0" encoding="UTF-8"?><TiffTagDescData version="1.0">'
        "<HeightInfo><HeightDataPerPixelX>125000</HeightDataPerPixelX>"
        "<HeightDataPerPixelY>130000</HeightDataPerPixelY>"
        "<HeightDataPerPixelZ>1</HeightDataPerPixelZ>"
        "<HeightDataUnitX>2</HeightDataUnitX><HeightDataUnitY>2</HeightDataUnitY>"
        "<HeightDataUnitZ>2</HeightDataUnitZ></HeightInfo></TiffTagDescData>"
    )
    exif_xml = (
        '<?xml version="1.0" encoding="UTF-8"?><ExifTagDescData version="1.0">'
        "<ImageCommonSettingsInfo><MakerCalibrationValueX>1002000</MakerCalibrationValueX>"
        "<MakerCalibrationValueY>999000</MakerCalibrationValueY>"
        "<MakerCalibrationValueZ>998000</MakerCalibrationValueZ>"
        "</ImageCommonSettingsInfo></ExifTagDescData>"
    ).encode() + b"\0"
    h = rough(nx, ny, seed, rms=2.0e5) + 1.0e6  # counts of 1 pm
    heights = np.round(h).astype("<u4").tobytes()
    rgb = (np.arange(nx * ny * 3) % 251).astype(np.uint8).tobytes()
    out = bytearray(b"II*\0\0\0\0\0")
    # Strips first, then the Exif directory, then the pages (each pointing to the next).
    rgb_at = len(out)
    out += rgb
    h_at = len(out)
    out += heights
    exif_at = len(out)
    # As ASCII: SurfaceTopography 1.27.1 drops the tag's value when it is UNDEFINED bytes.
    out += tiff_ifd(exif_at, [(41995, 2, len(exif_xml), exif_xml)])
    common = lambda: [(256, *long(nx)), (257, *long(ny)), (259, *short(1)), (278, *long(ny))]
    page0 = common() + [
        (258, 3, 3, struct.pack("<HHH", 8, 8, 8)),
        (262, *short(2)),
        (270, *ascii(desc)),
        (273, *long(rgb_at)),
        (277, *short(3)),
        (279, *long(len(rgb))),
        (34665, *long(exif_at)),
    ]
    page1 = common() + [
        (258, *short(32)),
        (262, *short(1)),
        (270, *ascii("HEIGHT")),
        (273, *long(h_at)),
        (277, *short(1)),
        (279, *long(len(heights))),
        (339, *short(1)),
    ]
    if len(out) % 2:
        out += b"\0"
    p0_at = len(out)
    p0_len = len(tiff_ifd(p0_at, page0))
    p1_at = p0_at + p0_len + (p0_len % 2)
    out += tiff_ifd(p0_at, page0, p1_at)
    out += b"\0" * (p1_at - len(out))
    out += tiff_ifd(p1_at, page1)
    struct.pack_into("<I", out, 4, p0_at)
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(out)


# --- Keyence ZON ----------------------------------------------------------------------

def zon_array(values, elem):
    """The 16-byte header (width, height, element size, row bytes) and the rows, each
    padded with 8 bytes."""
    ny, nx = values.shape
    row = nx * elem + 8
    out = struct.pack("<iiii", nx, ny, elem, row)
    for line in values:
        out += line.tobytes() + b"\xee" * 8
    return out


def zon(name, nx, ny, seed):
    import io
    import zipfile

    import zstandard

    h = np.round(rough(nx, ny, seed, rms=4000.0)).astype("<i4")  # counts of 0.1 nm
    valid = np.zeros((ny, nx), dtype=np.uint8)
    valid[3:6, 10:14] = 1  # not measured
    valid[20, 5] = 2
    valid[7, 7] = 4  # another flag bit: measured
    entries = {
        "cbc1d39b-215f-4d56-a20e-cf8e5f570755":
            b"<?xml version='1.0'?><Device><DeviceModelName>VR-5000</DeviceModelName>"
            b"<DeviceSerialId>0</DeviceSerialId></Device>",
        "1d35862b-3b48-4df2-9235-833ef590b043":
            b"<?xml version='1.0'?><Scan><ScanDateTime>2024-01-02T03:04:05</ScanDateTime></Scan>",
        "686613b8-27b5-4a29-8ffc-438c2780873e":
            b"<?xml version='1.0'?><Calibration><XYCalibration><MeterPerPixel>2.35e-6"
            b"</MeterPerPixel></XYCalibration><ZCalibration><MeterPerUnit>1e-10</MeterPerUnit>"
            b"</ZCalibration></Calibration>",
        "4cdb0c75-5706-48cc-a9a1-adf395d609ae": zon_array(h, 4),
        "9e7ca6dd-0e6a-4d7b-8986-f0a7b773c916": zon_array(valid, 1),
    }
    z = io.BytesIO()
    zc = zstandard.ZstdCompressor(level=3, write_content_size=True)
    with zipfile.ZipFile(z, "w", zipfile.ZIP_STORED) as archive:
        for uuid, content in entries.items():
            info = zipfile.ZipInfo(uuid, date_time=(2024, 1, 2, 3, 4, 6))
            archive.writestr(info, zc.compress(content))
    bmp = b"BM" + b"\0" * 60
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(b"KPK1" + struct.pack("<I", len(bmp)) + bmp + z.getvalue())


# --- Zygo DATX -------------------------------------------------------------------------

def datx(name, nx, ny, seed, latest, chunks=None):
    """A DATX file: /MetaData (category, key, value) naming the surface's path, and
    /Measurement/Surface, float64 heights in µm stored (rows = y, columns = x), with the
    `Unit`, `No Data` and X/Y/Z converter attributes. `latest`: HDF5's newest structures
    (superblock 3, version 2 object headers, link messages; data contiguous, or in `chunks`
    indexed as HDF5 1.10 does); otherwise the oldest (superblock 0, symbol-table groups)
    with chunked data (version 1 B-tree). Chunked data are shuffled and deflated."""
    import h5py

    h = rough(nx, ny, seed, rms=0.05)  # µm
    no_data = 1.0e38
    h[2:4, 5:9] = no_data
    h[ny - 1, 0] = np.nan
    s = h5py.string_dtype()
    conv = np.dtype([("Category", s), ("BaseUnit", s), ("DisplayUnit", s), ("Parameters", "<f8", (4,))])
    meta = np.array(
        [
            (b"Root", b"Measurement", b"{m}"),
            (b"{m}", b"Surface", b"{s}"),
            (b"{s}", b"Path", b"/Measurement/Surface"),
        ],
        dtype=[("Category", s), ("Key", s), ("Value", s)],
    )
    # Chunked data as HDF5 1.10 writes them (layout version 4; h5py's own library would
    # write version 5 with "latest", which this reader refuses by name).
    if latest and chunks is not None:
        libver = ("v110", "v110")
    elif latest:
        libver = ("latest", "latest")
    else:
        libver = ("earliest", "latest")
    with h5py.File(os.path.join(HERE, name), "w", libver=libver, track_order=False) as f:
        f.create_dataset("MetaData", data=meta, track_times=False)
        g = f.create_group("Measurement")
        g.attrs["Comment"] = "synthetic, written by make_synthetic.py"
        if latest and chunks is None:
            d = g.create_dataset("Surface", data=h, track_times=False)
        else:
            d = g.create_dataset("Surface", data=h, chunks=chunks or (16, 16), compression="gzip", shuffle=True, track_times=False)
        d.attrs["Unit"] = np.array([b"MicroMeters"], dtype=s)
        d.attrs["No Data"] = np.array([no_data])
        d.attrs["X Converter"] = np.array([("LateralCat", "Pixels", "MicroMeters", [0.0, 1.25e-6, 0.0, 0.0])], dtype=conv)
        d.attrs["Y Converter"] = np.array([("LateralCat", "Pixels", "MicroMeters", [0.0, 1.5e-6, 0.0, 0.0])], dtype=conv)
        d.attrs["Z Converter"] = np.array([("HeightCat", "MicroMeters", "NanoMeters", [633e-9, 1.0, 0.0, 0.0])], dtype=conv)


if __name__ == "__main__":
    lext("lext-synth.lext", 96, 64, 36)
    zon("zon-kpk1-synth.zon", 80, 72, 37)
    datx("datx-synth.datx", 70, 50, 38, latest=False)
    datx("datx-synth-latest.datx", 40, 30, 39, latest=True)
    # HDF5 1.10's fixed-array (8 × 8 chunks) and single-chunk indexes.
    datx("datx-synth-fixed-array.datx", 36, 28, 40, latest=True, chunks=(8, 8))
    datx("datx-synth-single-chunk.datx", 24, 20, 41, latest=True, chunks=(20, 24))
