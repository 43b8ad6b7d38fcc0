//! What a render of a given resolution holds in memory at its peak, and
//! whether this machine can give it that much: checked before the film is
//! allocated, so a resolution too large for the machine is an error with the
//! numbers rather than an abort half-way.

/// Bytes per pixel at a render's peak: the film's fixed-point sums (48), the
/// linear-sRGB image (12), the encoded EXR (12) and the PNG with its 8-bit
/// buffer (6). The film is written to disk streamed, without a second copy.
pub const PEAK_BYTES_PER_PIXEL: u64 = 48 + 12 + 12 + 6;

/// Bytes per spectral band and pixel at the peak of a render with bands:
/// the film's fixed-point sum (16), its mean in f64 (8), the f32 values
/// (4), the EXR channel (4) and the encoded EXR (4).
pub const PEAK_BYTES_PER_BAND: u64 = 16 + 8 + 4 + 4 + 4;

/// Bytes a `width × height` render holds at its peak.
pub fn needed_bytes(width: u32, height: u32) -> u64 {
    width as u64 * height as u64 * PEAK_BYTES_PER_PIXEL
}

/// Bytes a `width × height` render with `bands` spectral bands holds at its peak.
pub fn needed_bytes_with_bands(width: u32, height: u32, bands: usize) -> u64 {
    let pixels = width as u64 * height as u64;
    needed_bytes(width, height).saturating_add(
        pixels
            .saturating_mul(bands as u64)
            .saturating_mul(PEAK_BYTES_PER_BAND),
    )
}

/// Memory this process may still take: the smaller of the system's available
/// memory and what the address-space limit (`ulimit -v`) leaves; `None` where
/// neither can be read (then nothing is refused up front).
pub fn available_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok();
    let available = meminfo
        .as_deref()
        .and_then(|t| kib_field(t, "MemAvailable:"));
    let limits = std::fs::read_to_string("/proc/self/limits").ok();
    let status = std::fs::read_to_string("/proc/self/status").ok();
    let headroom = match (
        limits.as_deref().and_then(address_space_limit),
        status.as_deref().and_then(|t| kib_field(t, "VmSize:")),
    ) {
        (Some(limit), Some(used)) => Some(limit.saturating_sub(used)),
        _ => None,
    };
    match (available, headroom) {
        (Some(a), Some(h)) => Some(a.min(h)),
        (a, h) => a.or(h),
    }
}

/// A `Name:   1234 kB` field of /proc/meminfo or /proc/self/status, in bytes.
fn kib_field(text: &str, name: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with(name))?;
    let kib: u64 = line[name.len()..].split_whitespace().next()?.parse().ok()?;
    Some(kib.saturating_mul(1024))
}

/// The soft "Max address space" of /proc/self/limits in bytes (`None` when unlimited).
fn address_space_limit(text: &str) -> Option<u64> {
    let line = text.lines().find(|l| l.starts_with("Max address space"))?;
    line["Max address space".len()..]
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Refuses a `width × height` render that needs more memory than this
/// process can get, naming both numbers and the fix.
pub fn check_fits(width: u32, height: u32) -> Result<(), String> {
    check_fits_with_bands(width, height, 0)
}

/// [`check_fits`] for a render with `bands` spectral bands per pixel.
pub fn check_fits_with_bands(width: u32, height: u32, bands: usize) -> Result<(), String> {
    let need = needed_bytes_with_bands(width, height, bands);
    let per_pixel = PEAK_BYTES_PER_PIXEL + bands as u64 * PEAK_BYTES_PER_BAND;
    match available_bytes() {
        Some(have) if need > have => Err(format!(
            "a {width}×{height} render needs about {} of memory at its peak ({} bytes per \
             pixel: film sums and output images), and this process can get {}: lower the \
             resolution or the spectral bands (at most about {} pixels fit here)",
            gib(need),
            per_pixel,
            gib(have),
            have / per_pixel
        )),
        _ => Ok(()),
    }
}

fn gib(bytes: u64) -> String {
    format!("{:.2} GiB", bytes as f64 / (1u64 << 30) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_the_proc_fields() {
        let meminfo = "MemTotal:       24000000 kB\nMemAvailable:   2000000 kB\n";
        assert_eq!(kib_field(meminfo, "MemAvailable:"), Some(2_048_000_000));
        let limits = "Limit                     Soft Limit           Hard Limit           Units\n\
                      Max address space         2147483648           unlimited            bytes\n";
        assert_eq!(address_space_limit(limits), Some(2_147_483_648));
        let unlimited =
            "Max address space         unlimited            unlimited            bytes\n";
        assert_eq!(address_space_limit(unlimited), None);
        assert_eq!(needed_bytes(32768, 1024), (1 << 25) * PEAK_BYTES_PER_PIXEL);
        // A one-pixel render always fits.
        assert!(check_fits(1, 1).is_ok());
        assert!(check_fits_with_bands(1, 1, 256).is_ok());
        assert_eq!(needed_bytes_with_bands(40, 30, 0), needed_bytes(40, 30));
        assert_eq!(
            needed_bytes_with_bands(40, 30, 16) - needed_bytes(40, 30),
            1200 * 16 * PEAK_BYTES_PER_BAND
        );
    }
}
