//! A surface whose 2-D PSD is a radial PSD stretched along two perpendicular
//! axes (physics.md §15.2): the elliptical generalisation of
//! [`AnisotropicKc`](super::AnisotropicKc) to any radial law, e.g. a measured
//! one ([`TabulatedPsd`](super::TabulatedPsd)).
//!
//! ```text
//! P₂(ζ) = P_r(|(s_a ζ·a, s_b ζ·b)|),   s_a = √(Lx/Ly),  s_b = √(Ly/Lx),
//! a = (cos φ₀, sin φ₀),  b = (−sin φ₀, cos φ₀),
//! ```
//!
//! The stretch keeps areas (s_a s_b = 1), so σ² = ∫P₂ d²ζ = ∫P_r d²ζ: P_r is the
//! PSD of the surface seen in the de-stretched frame, and only the ratio Ly/Lx of
//! the two lengths is read. In the dimensionless u of the radial law (u = L·ζ,
//! L = [`RadialPsd::length_um`]) the stretched frequency is
//! u = L (s_a ζ·a, s_b ζ·b), and P₂(ζ) = σ² L² p(|u|).

use crate::BrdfError;

use super::RadialPsd;
use super::anisotropic::{AnisotropicKc, check_axes};
use super::kc::KcPsd;

/// What the anisotropic GHS needs of a stretched surface: its radial law in u
/// and the linear map ζ ↦ u.
pub trait StretchedPsd {
    /// The radial law in u.
    type Radial: RadialPsd + Clone;
    /// The radial law (its `length_um` is the unit of u the map below uses).
    fn radial(&self) -> Result<Self::Radial, BrdfError>;
    /// u of a frequency ζ = (ζx, ζy), rad/µm.
    fn to_u(&self, zx: f64, zy: f64) -> (f64, f64);
    /// ζ of a u (the inverse of [`to_u`](Self::to_u)).
    fn u_to_zeta(&self, ux: f64, uy: f64) -> (f64, f64);
    /// |det| of the map ζ ↦ u, µm²: d²u = area·d²ζ, and S(ζ; g) = area·S̃(|u|; g).
    fn area_um2(&self) -> f64;
    /// The largest |u| per unit |ζ|, µm (the reach of the S̃ table needed).
    fn reach_um(&self) -> f64;
    /// rms height σ, µm.
    fn sigma_um(&self) -> f64;
    /// Why the full GHS cannot be built for this surface, if it cannot.
    fn check_full(&self) -> Result<(), BrdfError> {
        Ok(())
    }
}

impl StretchedPsd for AnisotropicKc {
    type Radial = KcPsd;

    fn radial(&self) -> Result<KcPsd, BrdfError> {
        AnisotropicKc::radial(self, self.lx_um().max(self.ly_um()))
    }

    fn to_u(&self, zx: f64, zy: f64) -> (f64, f64) {
        AnisotropicKc::to_u(self, zx, zy)
    }

    fn u_to_zeta(&self, ux: f64, uy: f64) -> (f64, f64) {
        AnisotropicKc::from_u(self, ux, uy)
    }

    fn area_um2(&self) -> f64 {
        self.lx_um() * self.ly_um()
    }

    fn reach_um(&self) -> f64 {
        self.lx_um().max(self.ly_um())
    }

    fn sigma_um(&self) -> f64 {
        AnisotropicKc::sigma_um(self)
    }

    fn check_full(&self) -> Result<(), BrdfError> {
        if self.gamma() < super::kc::GAMMA_MIN_FULL {
            return Err(BrdfError::OutOfRange {
                name: "gamma",
                value: self.gamma(),
                valid: "≥ 1.05 for the full GHS (use the SSA below)",
            });
        }
        Ok(())
    }
}

/// A radial PSD stretched along axes at φ₀ with lengths in the ratio Ly/Lx
/// (area kept).
#[derive(Clone, Debug, PartialEq)]
pub struct EllipticalPsd<P> {
    radial: P,
    lx_um: f64,
    ly_um: f64,
    angle_rad: f64,
    /// L·s_a, L·s_b: the map ζ ↦ u along a and b, µm.
    scale_um: (f64, f64),
    /// cos φ₀, sin φ₀
    cs: (f64, f64),
}

impl<P: RadialPsd> EllipticalPsd<P> {
    /// Validates and builds: Lx, Ly ∈ [0.03, 1000] µm (only Ly/Lx is used), φ₀
    /// finite (radians from the tangent x towards y).
    pub fn new(radial: P, lx_um: f64, ly_um: f64, angle_rad: f64) -> Result<Self, BrdfError> {
        check_axes(lx_um, ly_um, angle_rad)?;
        let l = radial.length_um();
        let s = libm::sqrt(ly_um / lx_um);
        Ok(EllipticalPsd {
            radial,
            lx_um,
            ly_um,
            angle_rad,
            scale_um: (l / s, l * s),
            cs: (libm::cos(angle_rad), libm::sin(angle_rad)),
        })
    }

    /// The radial law of the de-stretched frame.
    pub fn radial_psd(&self) -> &P {
        &self.radial
    }

    /// Lx as given, µm (only Ly/Lx is used).
    pub fn lx_um(&self) -> f64 {
        self.lx_um
    }

    /// Ly as given, µm.
    pub fn ly_um(&self) -> f64 {
        self.ly_um
    }

    /// φ₀, radians from the tangent x towards y.
    pub fn angle_rad(&self) -> f64 {
        self.angle_rad
    }

    /// P₂(ζ), µm⁴; ∫ P₂ d²ζ = σ².
    pub fn psd(&self, zx: f64, zy: f64) -> f64 {
        let (ux, uy) = self.map_to_u(zx, zy);
        let (s, l) = (self.radial.sigma_um(), self.radial.length_um());
        s * s * l * l * self.radial.unit_psd_u(libm::hypot(ux, uy))
    }

    #[inline]
    fn map_to_u(&self, zx: f64, zy: f64) -> (f64, f64) {
        let (c, s) = self.cs;
        (
            self.scale_um.0 * (c * zx + s * zy),
            self.scale_um.1 * (c * zy - s * zx),
        )
    }
}

impl<P: RadialPsd + Clone> StretchedPsd for EllipticalPsd<P> {
    type Radial = P;

    fn radial(&self) -> Result<P, BrdfError> {
        Ok(self.radial.clone())
    }

    fn to_u(&self, zx: f64, zy: f64) -> (f64, f64) {
        self.map_to_u(zx, zy)
    }

    fn u_to_zeta(&self, ux: f64, uy: f64) -> (f64, f64) {
        let (c, s) = self.cs;
        let (za, zb) = (ux / self.scale_um.0, uy / self.scale_um.1);
        (c * za - s * zb, s * za + c * zb)
    }

    fn area_um2(&self) -> f64 {
        self.scale_um.0 * self.scale_um.1
    }

    fn reach_um(&self) -> f64 {
        self.scale_um.0.max(self.scale_um.1)
    }

    fn sigma_um(&self) -> f64 {
        self.radial.sigma_um()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stretched_kc_is_the_anisotropic_kc_of_the_same_area() {
        // KC with Lc = √(Lx Ly) stretched by Ly/Lx is the anisotropic KC (Lx, Ly).
        let (lx, ly, phi) = (0.4, 3.6, 0.9);
        let iso = KcPsd::new(0.2, libm::sqrt(lx * ly), 2.7).unwrap();
        let e = EllipticalPsd::new(iso, lx, ly, phi).unwrap();
        let a = AnisotropicKc::new(0.2, lx, ly, phi, 2.7).unwrap();
        for (zx, zy) in [(0.0, 0.1), (1.3, -0.4), (-7.0, 2.0), (30.0, 31.0)] {
            let (p, q) = (e.psd(zx, zy), a.psd(zx, zy));
            assert!((p / q - 1.0).abs() < 1e-12, "{p} vs {q}");
            let (ux, uy) = StretchedPsd::to_u(&e, zx, zy);
            let (x, y) = StretchedPsd::u_to_zeta(&e, ux, uy);
            assert!((x - zx).abs() < 1e-12 && (y - zy).abs() < 1e-12);
        }
        assert!((StretchedPsd::area_um2(&e) - iso.length_um().powi(2)).abs() < 1e-12);
    }

    #[test]
    fn out_of_range_names_the_key() {
        let iso = KcPsd::new(0.2, 1.0, 2.7).unwrap();
        for (lx, ly, a, key) in [
            (0.0, 1.0, 0.0, "lx_um"),
            (1.0, f64::NAN, 0.0, "ly_um"),
            (1.0, 1.0, f64::INFINITY, "angle_deg"),
        ] {
            match EllipticalPsd::new(iso, lx, ly, a) {
                Err(BrdfError::OutOfRange { name, .. }) => assert_eq!(name, key),
                other => panic!("{other:?}"),
            }
        }
    }
}
