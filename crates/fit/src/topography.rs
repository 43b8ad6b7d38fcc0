//! The in-memory height map every reader produces.

/// A height map or a profile, in SI units.
///
/// `heights[y * nx + x]`; x is the fast-scan axis (one scan line is one row).
/// A profile has `ny == 1`. Invalid points are NaN.
#[derive(Debug, Clone, PartialEq)]
pub struct Topography {
    /// Points along x (fast axis).
    pub nx: usize,
    /// Lines (1 for a profile).
    pub ny: usize,
    /// Pixel spacing along x [m] (scan length / nx).
    pub dx: f64,
    /// Pixel spacing along y [m] (equal to `dx` for profiles).
    pub dy: f64,
    /// Heights [m], row-major, NaN where invalid.
    pub heights: Vec<f64>,
    /// Channel or data-set name as stored in the file.
    pub channel: String,
    /// Short name of the reader that produced this map.
    pub format: &'static str,
}

impl Topography {
    /// True for a single profile (one line).
    pub fn is_profile(&self) -> bool {
        self.ny == 1
    }

    /// A single column (`nx == 1`, several lines) as the profile along y it is, so it is
    /// analysed like a single row; anything else unchanged.
    pub fn column_as_profile(self) -> Topography {
        if self.nx == 1 && self.ny > 1 {
            Topography {
                nx: self.ny,
                ny: 1,
                dx: self.dy,
                ..self
            }
        } else {
            self
        }
    }

    /// One scan line.
    pub fn line(&self, y: usize) -> &[f64] {
        &self.heights[y * self.nx..(y + 1) * self.nx]
    }

    /// Number of NaN points.
    pub fn invalid_count(&self) -> usize {
        self.heights.iter().filter(|h| !h.is_finite()).count()
    }

    /// Physical size along x [m] (`nx·dx`, the SurfaceTopography convention).
    pub fn size_x(&self) -> f64 {
        self.nx as f64 * self.dx
    }

    /// Physical size along y [m].
    pub fn size_y(&self) -> f64 {
        self.ny as f64 * self.dy
    }
}
