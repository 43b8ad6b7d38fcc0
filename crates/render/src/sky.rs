//! A daylight environment: the analytic sky of Preetham, Shirley & Smits,
//! *A Practical Analytic Model for Daylight* (SIGGRAPH 1999), with its sun,
//! evaluated spectrally.
//!
//! * Sky: per direction, the Perez et al. (1993) distribution with
//!   Preetham's turbidity-linear coefficients gives luminance Y and
//!   chromaticity (x, y) relative to the zenith values (Preetham's zenith
//!   luminance and chromaticity fits); (x, y) becomes a spectrum through the
//!   CIE daylight basis S0 + M1·S1 + M2·S2 (CIE 15:2004 §3.1), scaled to Y.
//!   Below the horizon: a Lambertian ground of albedo ρ lit by this sky and
//!   sun, radiance ρ·E_h(λ)/π.
//! * Sun: a uniform disk of the mean solar angular radius, whose spectral
//!   radiance is the extraterrestrial spectrum attenuated along the
//!   relative air mass by Rayleigh scattering, Ångström aerosol
//!   (α = 1.3, β = 0.04608 T − 0.04586), ozone (0.35 cm), mixed gases and
//!   water vapour (2 cm): Preetham's Appendix A.2. The extraterrestrial
//!   spectrum and absorption coefficients are those of Bird & Riordan's
//!   SPECTRL2 (NREL TR-215-2436, 1984), `data/spectra/sun_spectrl2.csv`.
//!
//! Radiance is physical (cd/m², W m⁻² sr⁻¹ nm⁻¹) times the scene's `scale`.
//! Emission is carried as four coefficients on the basis
//! (S0, S1, S2, sun spectrum), so a hero path evaluates its wavelengths with
//! four table lookups each.
//!
//! Sampling: a mixture of the sun cone (probability `q`, the sun's share of
//! ∫L dω clamped to [0.2, 0.8]) and a 256 × 128 lat-long table of sky and
//! ground luminance (each cell weighted by the largest luminance at its
//! centre and corners, times sin θ, so that L/pdf stays bounded inside a
//! cell). The sun is not in the table: the disk is 0.53° across, smaller
//! than a cell, and sampling it exactly is what keeps it from producing
//! fireflies.

use crate::distribution::Distribution2D;
use crate::spectrum::{Cie, LAMBDA_MAX, LAMBDA_MIN, parse_csv_rows};
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::OnceLock;

const DAYLIGHT_CSV: &str = include_str!("../../../data/spectra/cie_daylight_components.csv");
const SUN_CSV: &str = include_str!("../../../data/spectra/sun_spectrl2.csv");

/// Mean angular radius of the sun seen from the Earth (695 700 km at 1 au), radians.
pub const SUN_ANGULAR_RADIUS: f64 = 0.004_650_5;
/// Luminous efficacy of 555 nm radiation, lm/W (the CIE's K_m).
pub const K_M: f64 = 683.0;
/// Ångström exponent of Preetham's aerosol model.
pub const ANGSTROM_ALPHA: f64 = 1.3;
/// Ozone column of Preetham's sun model, cm at STP.
pub const OZONE_CM: f64 = 0.35;
/// Precipitable water of Preetham's sun model, cm.
pub const WATER_CM: f64 = 2.0;

const TABLE_W: usize = 256;
const TABLE_H: usize = 128;

/// Sky settings as a scene gives them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SkyParams {
    /// Atmospheric turbidity T, 2–10 (2: very clear, 3: clear, 6+: hazy).
    pub turbidity: f64,
    /// Sun elevation above the horizon, degrees, (0, 90].
    pub sun_elevation_deg: f64,
    /// Sun azimuth, degrees: 0 toward −z, 90 toward +x (as the u axis of lat-long maps).
    pub sun_azimuth_deg: f64,
    /// Multiplies physical radiance (luminance in cd/m²) into scene units.
    pub scale: f64,
    /// Whether the sun disk emits (the sky is lit as if it were there either way).
    pub sun: bool,
    /// Albedo of the Lambertian ground below the horizon, [0, 1].
    pub ground_albedo: f64,
}

impl Default for SkyParams {
    fn default() -> Self {
        SkyParams {
            turbidity: 2.5,
            sun_elevation_deg: 35.0,
            sun_azimuth_deg: 0.0,
            scale: 1e-4,
            sun: true,
            ground_albedo: 0.2,
        }
    }
}

/// Spectral tables on a 1 nm grid over 360–830 nm: S0, S1, S2 and the
/// extraterrestrial solar irradiance (W m⁻² nm⁻¹), with the absorption
/// coefficients of ozone, mixed gases and water vapour.
struct Tables {
    /// Per nm: [S0, S1, S2, E_et, k_o, k_g, k_w].
    rows: Vec<[f64; 7]>,
    /// ∫S_i ȳ / ∫ȳ for S0, S1, S2.
    lum: [f64; 3],
}

fn lerp_rows(rows: &[Vec<f64>], col: usize, l: f64) -> f64 {
    let i = rows.partition_point(|r| r[0] <= l);
    if i == 0 || i >= rows.len() {
        return rows
            .get(i.min(rows.len() - 1))
            .filter(|r| r[0] == l)
            .map_or(0.0, |r| r[col]);
    }
    let (a, b) = (&rows[i - 1], &rows[i]);
    let t = (l - a[0]) / (b[0] - a[0]);
    a[col] + t * (b[col] - a[col])
}

fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    T.get_or_init(|| {
        let day = parse_csv_rows(DAYLIGHT_CSV, 4).expect("bundled daylight table is valid");
        let sun = parse_csv_rows(SUN_CSV, 5).expect("bundled SPECTRL2 table is valid");
        let cie = Cie::get();
        let n = (LAMBDA_MAX - LAMBDA_MIN) as usize + 1;
        let mut rows = Vec::with_capacity(n);
        let mut lum = [0.0; 3];
        for i in 0..n {
            let l = LAMBDA_MIN + i as f64;
            let r = [
                lerp_rows(&day, 1, l),
                lerp_rows(&day, 2, l),
                lerp_rows(&day, 3, l),
                lerp_rows(&sun, 1, l),
                lerp_rows(&sun, 3, l),
                lerp_rows(&sun, 4, l),
                lerp_rows(&sun, 2, l),
            ];
            // Trapezoid on the 1 nm grid, as the CIE integral itself.
            let w = if i == 0 || i == n - 1 { 0.5 } else { 1.0 };
            for k in 0..3 {
                lum[k] += w * r[k] * cie.xyz(l)[1];
            }
            rows.push(r);
        }
        for v in &mut lum {
            *v /= cie.y_integral();
        }
        Tables { rows, lum }
    })
}

#[inline]
fn table_at(l: f64) -> Option<(usize, f64)> {
    if !(LAMBDA_MIN..=LAMBDA_MAX).contains(&l) {
        return None;
    }
    let x = l - LAMBDA_MIN;
    let i = (x as usize).min((LAMBDA_MAX - LAMBDA_MIN) as usize - 1);
    Some((i, x - i as f64))
}

/// Relative optical air mass at solar zenith angle `zenith` (rad), Kasten (1966),
/// the formula of Preetham's Appendix A.2.
pub fn relative_air_mass(zenith: f64) -> f64 {
    let deg = zenith.to_degrees();
    1.0 / (zenith.cos() + 0.15 * (93.885 - deg).powf(-1.253))
}

/// Ångström turbidity coefficient β of Preetham's turbidity T.
pub fn angstrom_beta(turbidity: f64) -> f64 {
    0.046_08 * turbidity - 0.045_86
}

/// Direct-normal spectral irradiance of the sun at the ground (W m⁻² nm⁻¹)
/// at `lambda_nm` and solar zenith `zenith` (rad), through an atmosphere
/// with Ångström coefficients (`beta`, `alpha`), `ozone_cm` of ozone and
/// `water_cm` of precipitable water (Preetham 1999, Appendix A.2).
pub fn sun_direct_normal(
    lambda_nm: f64,
    zenith: f64,
    beta: f64,
    alpha: f64,
    ozone_cm: f64,
    water_cm: f64,
) -> f64 {
    let t = tables();
    let Some((i, f)) = table_at(lambda_nm) else {
        return 0.0;
    };
    let at = |c: usize| t.rows[i][c] + f * (t.rows[i + 1][c] - t.rows[i][c]);
    let m = relative_air_mass(zenith);
    let um = lambda_nm * 1e-3;
    let rayleigh = (-0.008_735 * um.powf(-4.08) * m).exp();
    let aerosol = (-beta * um.powf(-alpha) * m).exp();
    let ozone = (-at(4) * ozone_cm * m).exp();
    let kg = at(5) * m;
    let gases = (-1.41 * kg / (1.0 + 118.93 * kg).powf(0.45)).exp();
    let kw = at(6) * water_cm * m;
    let water = (-0.2385 * kw / (1.0 + 20.07 * kw).powf(0.45)).exp();
    at(3) * rayleigh * aerosol * ozone * gases * water
}

/// Coefficients (c0, c1, c2) with Σ cᵢ Sᵢ(λ) the CIE daylight spectrum of
/// chromaticity (`x`, `y`) scaled to unit luminance (∫S ȳ / ∫ȳ = 1), or
/// `None` where the CIE M1/M2 formulas break down (far off the daylight locus).
pub fn daylight_coefficients(x: f64, y: f64) -> Option<[f64; 3]> {
    let d = 0.0241 + 0.2562 * x - 0.7341 * y;
    if d.abs() < 1e-6 {
        return None;
    }
    let m1 = (-1.3515 - 1.7703 * x + 5.9114 * y) / d;
    let m2 = (0.0300 - 31.4424 * x + 30.0717 * y) / d;
    let lum = tables().lum;
    let y_unit = lum[0] + m1 * lum[1] + m2 * lum[2];
    (y_unit.is_finite() && y_unit > 0.0).then(|| [1.0 / y_unit, m1 / y_unit, m2 / y_unit])
}

/// Σ cᵢ Bᵢ(λ) over the basis (S0, S1, S2, extraterrestrial solar irradiance)
/// times the sun's transmittance is not linear, so the fourth basis function
/// is the sun's own spectral radiance at the ground, stored per sky.
#[derive(Clone, Debug)]
struct Basis {
    /// Per nm over 360–830: [S0, S1, S2, sun radiance in scene units per unit coefficient].
    rows: Vec<[f64; 4]>,
}

impl Basis {
    #[inline]
    fn eval(&self, c: &[f64; 4], lambda: f64) -> f64 {
        let Some((i, f)) = table_at(lambda) else {
            return 0.0;
        };
        let (a, b) = (&self.rows[i], &self.rows[i + 1]);
        let mut s = 0.0;
        for k in 0..4 {
            s += c[k] * (a[k] + f * (b[k] - a[k]));
        }
        s
    }
}

/// Perez et al. (1993) distribution (1 + A e^{B/cosθ})(1 + C e^{Dγ} + E cos²γ).
#[inline]
fn perez(p: &[f64; 5], cos_theta: f64, gamma: f64, cos_gamma: f64) -> f64 {
    (1.0 + p[0] * (p[1] / cos_theta.max(1e-6)).exp())
        * (1.0 + p[2] * (p[3] * gamma).exp() + p[4] * cos_gamma * cos_gamma)
}

/// Preetham's distribution coefficients [A..E] for Y, x and y at turbidity `t`.
fn perez_coefficients(t: f64) -> [[f64; 5]; 3] {
    [
        [
            0.1787 * t - 1.4630,
            -0.3554 * t + 0.4275,
            -0.0227 * t + 5.3251,
            0.1206 * t - 2.5771,
            -0.0670 * t + 0.3703,
        ],
        [
            -0.0193 * t - 0.2592,
            -0.0665 * t + 0.0008,
            -0.0004 * t + 0.2125,
            -0.0641 * t - 0.8989,
            -0.0033 * t + 0.0452,
        ],
        [
            -0.0167 * t - 0.2608,
            -0.0950 * t + 0.0092,
            -0.0079 * t + 0.2102,
            -0.0441 * t - 1.6537,
            -0.0109 * t + 0.0529,
        ],
    ]
}

/// Preetham's zenith luminance (kcd/m²) and chromaticity at turbidity `t`,
/// solar zenith `ts` (rad).
pub fn zenith_values(t: f64, ts: f64) -> [f64; 3] {
    let chi = (4.0 / 9.0 - t / 120.0) * (PI - 2.0 * ts);
    let yz = (4.0453 * t - 4.9710) * chi.tan() - 0.2155 * t + 2.4192;
    let th = [ts * ts * ts, ts * ts, ts, 1.0];
    let tt = [t * t, t, 1.0];
    const MX: [[f64; 4]; 3] = [
        [0.00166, -0.00375, 0.00209, 0.0],
        [-0.02903, 0.06377, -0.03202, 0.00394],
        [0.11693, -0.21196, 0.06052, 0.25886],
    ];
    const MY: [[f64; 4]; 3] = [
        [0.00275, -0.00610, 0.00317, 0.0],
        [-0.04214, 0.08970, -0.04153, 0.00516],
        [0.15346, -0.26756, 0.06670, 0.26688],
    ];
    let poly = |m: &[[f64; 4]; 3]| -> f64 {
        (0..3)
            .map(|r| tt[r] * (0..4).map(|c| m[r][c] * th[c]).sum::<f64>())
            .sum()
    };
    [yz, poly(&MX), poly(&MY)]
}

/// A built sky: model constants, the spectral basis and the sampling table.
#[derive(Debug)]
pub struct Sky {
    params: SkyParams,
    sun_dir: DVec3,
    /// 1 − cos of the sun's angular radius, without cancellation.
    sun_one_minus_cos: f64,
    perez: [[f64; 5]; 3],
    zenith: [f64; 3],
    /// F(0, θs) for Y, x, y: the Perez normalisation at the zenith.
    f_zenith: [f64; 3],
    basis: Basis,
    /// Coefficients of the ground radiance on the basis.
    ground: [f64; 4],
    /// Sun luminance in cd/m² (physical).
    sun_luminance: f64,
    dist: Distribution2D,
    /// Probability of sampling the sun cone.
    q_sun: f64,
}

impl SkyParams {
    /// Checks the parameters; errors name the offending one.
    fn check(&self) -> Result<(), String> {
        let p = self;
        if !(p.turbidity.is_finite() && (2.0..=10.0).contains(&p.turbidity)) {
            return Err(format!(
                "turbidity = {} is invalid: the Preetham model covers 2 (very clear) to 10 (hazy)",
                p.turbidity
            ));
        }
        if !(p.sun_elevation_deg.is_finite()
            && p.sun_elevation_deg > 0.0
            && p.sun_elevation_deg <= 90.0)
        {
            return Err(format!(
                "sun_elevation_deg = {} is invalid: expected (0, 90] (the model has no night sky)",
                p.sun_elevation_deg
            ));
        }
        if !p.sun_azimuth_deg.is_finite() {
            return Err("sun_azimuth_deg must be finite".into());
        }
        if !(p.scale.is_finite() && p.scale > 0.0) {
            return Err(format!(
                "scale = {} is invalid: expected a finite value > 0 (scene units per cd/m²)",
                p.scale
            ));
        }
        if !(p.ground_albedo.is_finite() && (0.0..=1.0).contains(&p.ground_albedo)) {
            return Err(format!(
                "ground_albedo = {} is invalid: expected 0..=1",
                p.ground_albedo
            ));
        }
        Ok(())
    }
}

/// The sun's column of the spectral basis, per table row (the other three
/// are the daylight basis S0, S1, S2): its radiance in scene units, from the
/// direct normal irradiance over the disk's solid angle `omega` with the sun
/// at zenith angle `ts`; and the sun's physical luminance, cd/m².
fn sun_basis_rows(p: &SkyParams, ts: f64, omega: f64) -> (Vec<[f64; 4]>, f64) {
    let cie = Cie::get();
    let t = tables();
    let beta = angstrom_beta(p.turbidity);
    let mut sun_lum = 0.0;
    let rows: Vec<[f64; 4]> = t
        .rows
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let l = LAMBDA_MIN + i as f64;
            let radiance =
                sun_direct_normal(l, ts, beta, ANGSTROM_ALPHA, OZONE_CM, WATER_CM) / omega;
            let w = if i == 0 || i == t.rows.len() - 1 {
                0.5
            } else {
                1.0
            };
            sun_lum += w * radiance * cie.xyz(l)[1];
            // Scene radiance S with ∫S ȳ/∫ȳ = scale · K_m ∫L ȳ.
            [
                r[0],
                r[1],
                r[2],
                p.scale * K_M * cie.y_integral() * radiance,
            ]
        })
        .collect();
    let sun_luminance = K_M * sun_lum;

    (rows, sun_luminance)
}

impl Sky {
    /// Builds the sky; errors name the offending parameter.
    pub fn new(p: SkyParams) -> Result<Sky, String> {
        p.check()?;
        let e = p.sun_elevation_deg.to_radians();
        let az = p.sun_azimuth_deg.to_radians();
        let sun_dir = DVec3::new(e.cos() * az.sin(), e.sin(), -e.cos() * az.cos()).normalize();
        let ts = PI / 2.0 - e;
        let perez_c = perez_coefficients(p.turbidity);
        let zenith = zenith_values(p.turbidity, ts);
        let f_zenith = [0, 1, 2].map(|k| perez(&perez_c[k], 1.0, ts, ts.cos()));

        // Sun radiance (W m⁻² sr⁻¹ nm⁻¹ → scene units) as the fourth basis column.
        let h = SUN_ANGULAR_RADIUS * 0.5;
        let sun_one_minus_cos = 2.0 * h.sin() * h.sin();
        let omega = 2.0 * PI * sun_one_minus_cos;
        let (rows, sun_luminance) = sun_basis_rows(&p, ts, omega);

        let mut sky = Sky {
            params: p,
            sun_dir,
            sun_one_minus_cos,
            perez: perez_c,
            zenith,
            f_zenith,
            basis: Basis { rows },
            ground: [0.0; 4],
            sun_luminance,
            dist: Distribution2D::new(&[1.0], 1, 1),
            q_sun: 0.0,
        };

        // Horizontal irradiance on the basis, by the midpoint rule over the
        // table's upper cells, then the ground radiance ρE/π.
        let dphi = 2.0 * PI / TABLE_W as f64;
        let dth = PI / TABLE_H as f64;
        let mut e_h = [0.0; 4];
        let mut sky_power = 0.0;
        // Cell-centre luminances of the upper half, kept for the sampling table.
        let mut centre = vec![0.0; TABLE_W * TABLE_H / 2];
        for j in 0..TABLE_H / 2 {
            let th = (j as f64 + 0.5) * dth;
            let dw = th.sin() * dth * dphi;
            for i in 0..TABLE_W {
                let d = dir_of(i as f64 + 0.5, j as f64 + 0.5);
                let yxy = sky.yxy(d);
                if let Some(c) = sky.coefficients_of_yxy(yxy) {
                    for k in 0..3 {
                        e_h[k] += c[k] * th.cos() * dw;
                    }
                }
                let l = (1000.0 * yxy[0]).max(0.0);
                centre[j * TABLE_W + i] = l;
                sky_power += l * dw;
            }
        }
        e_h[3] = omega * e.sin();
        sky.ground = e_h.map(|v| v * p.ground_albedo / PI);
        let ground_lum = sky.ground_luminance();

        let weights = sky.sampling_weights(&centre, ground_lum);
        sky.dist = Distribution2D::new(&weights, TABLE_W, TABLE_H);
        let ground_power = ground_lum * 2.0 * PI;
        let sun_power = if p.sun { sun_luminance * omega } else { 0.0 };
        sky.q_sun = if p.sun {
            (sun_power / (sun_power + sky_power + ground_power)).clamp(0.2, 0.8)
        } else {
            0.0
        };
        Ok(sky)
    }

    /// The weights of the sampling table: the brightest of each cell's
    /// centre (`centre`, the upper half's cell-centre luminances) and
    /// corners, times sin θ; the ground's luminance below the horizon.
    fn sampling_weights(&self, centre: &[f64], ground_lum: f64) -> Vec<f64> {
        let dth = PI / TABLE_H as f64;
        let corner = |i: usize, j: usize| -> f64 {
            if 2 * j > TABLE_H {
                ground_lum
            } else {
                self.luminance_y(dir_of(i as f64, j as f64))
            }
        };
        let corners: Vec<f64> = (0..=TABLE_H / 2)
            .flat_map(|j| (0..=TABLE_W).map(move |i| (i, j)))
            .map(|(i, j)| corner(i, j))
            .collect();
        let mut weights = Vec::with_capacity(TABLE_W * TABLE_H);
        for j in 0..TABLE_H {
            let th = (j as f64 + 0.5) * dth;
            for i in 0..TABLE_W {
                let l = if j < TABLE_H / 2 {
                    let c = |a: usize, b: usize| corners[b * (TABLE_W + 1) + a];
                    centre[j * TABLE_W + i]
                        .max(c(i, j))
                        .max(c(i + 1, j))
                        .max(c(i, j + 1))
                        .max(c(i + 1, j + 1))
                } else {
                    ground_lum
                };
                weights.push(l.max(0.0) * th.sin());
            }
        }
        weights
    }

    /// The parameters.
    pub fn params(&self) -> &SkyParams {
        &self.params
    }

    /// Unit direction toward the sun's centre.
    pub fn sun_direction(&self) -> DVec3 {
        self.sun_dir
    }

    /// Preetham's zenith luminance (kcd/m²) and chromaticity x, y.
    pub fn zenith(&self) -> [f64; 3] {
        self.zenith
    }

    /// Sun luminance, cd/m² (physical, before `scale`).
    pub fn sun_luminance(&self) -> f64 {
        self.sun_luminance
    }

    /// Solid angle of the sun disk, sr.
    pub fn sun_solid_angle(&self) -> f64 {
        2.0 * PI * self.sun_one_minus_cos
    }

    /// Probability that [`Sky::sample`] draws from the sun cone.
    pub fn sun_probability(&self) -> f64 {
        self.q_sun
    }

    /// Sky luminance Y (kcd/m²) and chromaticity (x, y) toward `d` above the
    /// horizon (the Perez ratios to the zenith values); the sun disk is not included.
    pub fn yxy(&self, d: DVec3) -> [f64; 3] {
        let cos_t = d.y;
        let cos_g = d.dot(self.sun_dir).clamp(-1.0, 1.0);
        let g = cos_g.acos();
        [0, 1, 2]
            .map(|k| self.zenith[k] * perez(&self.perez[k], cos_t, g, cos_g) / self.f_zenith[k])
    }

    /// Physical luminance of sky or ground toward `d` (cd/m²), sun disk excluded.
    pub fn luminance_physical(&self, d: DVec3) -> f64 {
        if d.y < 0.0 {
            return self.ground_luminance() / self.params.scale;
        }
        self.luminance_y(d)
    }

    /// Sky luminance above the horizon (cd/m²) from the Y channel alone.
    fn luminance_y(&self, d: DVec3) -> f64 {
        let cos_g = d.dot(self.sun_dir).clamp(-1.0, 1.0);
        let y = self.zenith[0] * perez(&self.perez[0], d.y, cos_g.acos(), cos_g) / self.f_zenith[0];
        (1000.0 * y).max(0.0)
    }

    /// Ground luminance in scene units.
    fn ground_luminance(&self) -> f64 {
        let lum = tables().lum;
        let sun_lum = self.sun_luminance * self.params.scale;
        (self.ground[0] * lum[0]
            + self.ground[1] * lum[1]
            + self.ground[2] * lum[2]
            + self.ground[3] * sun_lum)
            .max(0.0)
    }

    /// Sky-only coefficients (scene units) above the horizon.
    fn sky_coefficients(&self, d: DVec3) -> Option<[f64; 4]> {
        if d.y < 0.0 {
            return None;
        }
        self.coefficients_of_yxy(self.yxy(d))
    }

    /// Sky coefficients (scene units) of luminance Y (kcd/m²) and chromaticity x, y.
    fn coefficients_of_yxy(&self, [y, x, yy]: [f64; 3]) -> Option<[f64; 4]> {
        let c = daylight_coefficients(x, yy)
            .or_else(|| daylight_coefficients(self.zenith[1], self.zenith[2]))?;
        let k = self.params.scale * 1000.0 * y.max(0.0);
        Some([k * c[0], k * c[1], k * c[2], 0.0])
    }

    /// Radiance toward `d` (unit) as coefficients on (S0, S1, S2, sun).
    #[inline]
    pub fn coefficients(&self, d: DVec3) -> [f64; 4] {
        let Some(mut c) = self.sky_coefficients(d) else {
            return self.ground;
        };
        if self.params.sun && 1.0 - d.dot(self.sun_dir) <= self.sun_one_minus_cos {
            c[3] = 1.0;
        }
        c
    }

    /// Spectral radiance of coefficients `c` at `lambda` nm, scene units.
    #[inline]
    pub fn spectral(&self, c: &[f64; 4], lambda: f64) -> f64 {
        self.basis.eval(c, lambda)
    }

    /// Solid-angle density of [`Sky::sample`] toward `d`.
    pub fn pdf(&self, d: DVec3) -> f64 {
        let mut p = 0.0;
        if self.q_sun > 0.0 && 1.0 - d.dot(self.sun_dir) <= self.sun_one_minus_cos {
            p += self.q_sun / (2.0 * PI * self.sun_one_minus_cos);
        }
        let [u, v] = uv_of(d);
        let st = (v * PI).sin();
        if st > 0.0 {
            p += (1.0 - self.q_sun) * self.dist.pdf([u, v]) / (2.0 * PI * PI * st);
        }
        p
    }

    /// Draws a direction: the sun cone with probability q, else the table.
    /// Returns the direction, its density and its radiance coefficients.
    pub fn sample(&self, u: [f64; 2]) -> Option<(DVec3, f64, [f64; 4])> {
        let d = if u[0] < self.q_sun {
            let s = u[0] / self.q_sun;
            let one_minus = s * self.sun_one_minus_cos;
            let cos_t = 1.0 - one_minus;
            let sin_t = (one_minus * (2.0 - one_minus)).max(0.0).sqrt();
            let phi = 2.0 * PI * u[1];
            let (a, b) = brdf::frame::orthonormal_basis(self.sun_dir);
            (sin_t * phi.cos() * a + sin_t * phi.sin() * b + cos_t * self.sun_dir).normalize()
        } else {
            let s = ((u[0] - self.q_sun) / (1.0 - self.q_sun)).min(1.0 - f64::EPSILON);
            let (uv, _) = self.dist.sample([s, u[1]]);
            dir_of(uv[0] * TABLE_W as f64, uv[1] * TABLE_H as f64)
        };
        let pdf = self.pdf(d);
        (pdf > 0.0 && pdf.is_finite()).then(|| (d, pdf, self.coefficients(d)))
    }
}

/// Direction of table coordinates (column `i`, row `j`, fractional), +y up,
/// u = 0 toward −z increasing toward +x (the lat-long convention of `EnvMap`).
fn dir_of(i: f64, j: f64) -> DVec3 {
    let theta = j / TABLE_H as f64 * PI;
    let phi = i / TABLE_W as f64 * 2.0 * PI;
    let st = theta.sin();
    DVec3::new(st * phi.sin(), theta.cos(), -st * phi.cos())
}

fn uv_of(d: DVec3) -> [f64; 2] {
    let u = (d.x.atan2(-d.z) / (2.0 * PI)).rem_euclid(1.0);
    let v = d.y.clamp(-1.0, 1.0).acos() / PI;
    [u, v.min(1.0 - 1e-12)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_directions_round_trip() {
        for (i, j) in [(0.5, 0.5), (100.25, 40.0), (255.5, 127.5), (13.0, 64.5)] {
            let d = dir_of(i, j);
            let [u, v] = uv_of(d);
            assert!((u * TABLE_W as f64 - i).abs() < 1e-9, "{i} {j}: u {u}");
            assert!((v * TABLE_H as f64 - j).abs() < 1e-9, "{i} {j}: v {v}");
        }
    }

    #[test]
    fn sample_pdf_is_consistent_and_normalised() {
        let sky = Sky::new(SkyParams::default()).unwrap();
        // E[1/pdf] over samples = 4π (the sampled support is the whole sphere).
        let n = 200_000;
        let mut acc = 0.0;
        for k in 0..n {
            let u = [
                (k as f64 + 0.5) / n as f64,
                ((k * 7919) % n) as f64 / n as f64,
            ];
            let (d, pdf, _) = sky.sample(u).unwrap();
            assert!((pdf - sky.pdf(d)).abs() <= 1e-9 * pdf);
            acc += 1.0 / pdf;
        }
        let est = acc / n as f64;
        assert!((est / (4.0 * PI) - 1.0).abs() < 0.02, "E[1/pdf] = {est}");
    }
}
