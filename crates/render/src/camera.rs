//! A pinhole perspective camera.

use crate::geometry::Ray;
use glam::DVec3;

/// Pinhole camera; pixel (0, 0) is the top-left corner of the image.
#[derive(Clone, Debug)]
pub struct Camera {
    origin: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tan_half: f64,
    aspect: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

/// `v` normalised, where its length squared neither overflows nor underflows
/// to zero (1e-150 < |v| < 1e150: a camera's directions need no more).
fn unit(v: DVec3) -> Option<DVec3> {
    let l2 = v.length_squared();
    (l2.is_finite() && l2 > 1e-300).then(|| v / l2.sqrt())
}

impl Camera {
    /// Builds the camera; errors name the offending key.
    pub fn new(
        look_from: DVec3,
        look_at: DVec3,
        up: DVec3,
        fov_deg: f64,
        width: u32,
        height: u32,
    ) -> Result<Camera, String> {
        let d = look_at - look_from;
        if !d.is_finite() {
            return Err(format!(
                "`look_at` − `look_from` = {d} overflows f64: place the camera and the point \
                 it looks at within ~1e300 of each other"
            ));
        }
        if d == DVec3::ZERO {
            return Err("`look_at` must differ from `look_from`".into());
        }
        let forward = unit(d).ok_or_else(|| {
            format!(
                "`look_at` is {:e} from `look_from`, too far or too near for f64 to take \
                 the viewing direction from; place them between 1e-150 and 1e150 apart",
                d.abs().max_element()
            )
        })?;
        let right = unit(up).map(|u| forward.cross(u)).and_then(unit).ok_or(
            "`up` must not be parallel to the viewing direction, nor zero (`up` defaults to +y)",
        )?;
        let up = right.cross(forward);
        if !(fov_deg.is_finite() && fov_deg > 0.0 && fov_deg < 179.0) {
            return Err(format!(
                "fov_deg = {fov_deg} is invalid: expected 0 < fov_deg < 179 (degrees, vertical)"
            ));
        }
        Ok(Camera {
            origin: look_from,
            forward,
            right,
            up,
            tan_half: (0.5 * fov_deg.to_radians()).tan(),
            aspect: width as f64 / height as f64,
            width,
            height,
        })
    }

    /// Ray through continuous pixel coordinates (`x` right, `y` down).
    #[inline]
    pub fn ray(&self, x: f64, y: f64) -> Ray {
        let sx = (2.0 * x / self.width as f64 - 1.0) * self.tan_half * self.aspect;
        let sy = (1.0 - 2.0 * y / self.height as f64) * self.tan_half;
        let d = (self.forward + sx * self.right + sy * self.up).normalize();
        Ray { o: self.origin, d }
    }

    /// Eye position.
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// Continuous pixel coordinates where a world point projects, if in front.
    pub fn project(&self, p: DVec3) -> Option<(f64, f64)> {
        let d = p - self.origin;
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let sx = d.dot(self.right) / z / (self.tan_half * self.aspect);
        let sy = d.dot(self.up) / z / self.tan_half;
        Some((
            (sx + 1.0) * 0.5 * self.width as f64,
            (1.0 - sy) * 0.5 * self.height as f64,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_looks_forward_and_projection_inverts() {
        let c = Camera::new(
            DVec3::new(0.0, 0.0, 5.0),
            DVec3::ZERO,
            DVec3::Y,
            40.0,
            64,
            48,
        )
        .unwrap();
        let r = c.ray(32.0, 24.0);
        assert!((r.d - DVec3::NEG_Z).length() < 1e-12);
        let p = c.ray(10.5, 7.25).d * 3.0 + c.origin();
        let (x, y) = c.project(p).unwrap();
        assert!((x - 10.5).abs() < 1e-9 && (y - 7.25).abs() < 1e-9);
        assert!(Camera::new(DVec3::ZERO, DVec3::ZERO, DVec3::Y, 40.0, 1, 1).is_err());
        assert!(Camera::new(DVec3::ZERO, DVec3::Y, DVec3::Y, 40.0, 1, 1).is_err());
    }

    #[test]
    fn distinct_points_are_not_called_equal() {
        let at = |from: DVec3| Camera::new(from, DVec3::ZERO, DVec3::Y, 40.0, 1, 1).unwrap_err();
        // The difference overflows when squared, or underflows.
        for from in [
            DVec3::new(0.0, 1e300, 1e300),
            DVec3::new(0.0, 1e-300, 1e-300),
        ] {
            let e = at(from);
            assert!(!e.contains("must differ") && e.contains("apart"), "{e}");
        }
        let c = Camera::new(
            DVec3::new(1.7e308, 0.0, 0.0),
            DVec3::new(-1.7e308, 0.0, 0.0),
            DVec3::Y,
            40.0,
            1,
            1,
        );
        assert!(c.unwrap_err().contains("overflows"));
        assert!(at(DVec3::ZERO).contains("must differ"));
        let e = Camera::new(DVec3::Z, DVec3::ZERO, DVec3::Y, 180.0, 1, 1).unwrap_err();
        assert!(e.contains("< 179"), "{e}");
    }
}
