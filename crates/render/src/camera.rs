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
        let forward = (look_at - look_from)
            .try_normalize()
            .ok_or("`look_at` must differ from `look_from`")?;
        let right = forward
            .cross(up)
            .try_normalize()
            .ok_or("`up` must not be parallel to the viewing direction (`up` defaults to +y)")?;
        let up = right.cross(forward);
        if !(fov_deg.is_finite() && fov_deg > 0.0 && fov_deg < 179.0) {
            return Err(format!(
                "fov_deg = {fov_deg} is invalid: expected 0 < fov_deg < 179"
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
}
