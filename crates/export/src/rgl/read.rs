//! Reading an RGL measured-BSDF file and evaluating it as Mitsuba 3's and
//! pbrt-v4's `measured` plugins do (`src/bsdfs/measured.cpp`,
//! `MeasuredBxDF` in `src/pbrt/bxdfs.cpp`): the read-back half of the
//! export's proof, and a way to look inside any RGL file.

use brdf::DVec3;
use core::f64::consts::PI;

use crate::ExportError;
use crate::marginal::Marginal2D;
use crate::param::{elevation, phi_to_u, theta_to_u, u_to_phi, u_to_theta};
use crate::tensor::{self, Dtype, Field};

/// An RGL measured BSDF, ready to evaluate.
#[derive(Clone, Debug)]
pub struct RglTable {
    description: String,
    theta_i: Vec<f64>,
    phi_i: Vec<f64>,
    /// Wavelengths (nm) of a spectral file, `[0, 1, 2]` (channels) of an RGB one.
    wavelengths: Vec<f64>,
    spectral: bool,
    isotropic: bool,
    /// 1, or 2 / 4 when the file covers half / a quarter of the azimuths.
    reduction: i32,
    jacobian: bool,
    ndf: Marginal2D,
    sigma: Marginal2D,
    vndf: Marginal2D,
    luminance: Marginal2D,
    spectra: Marginal2D,
    /// Shape of the spectra field.
    shape: [usize; 5],
}

/// A direction drawn from the table's own sampler.
#[derive(Clone, Copy, Debug)]
pub struct TableSample {
    /// The outgoing direction.
    pub wo: DVec3,
    /// Its solid-angle density.
    pub pdf: f64,
}

/// Where a pair of directions falls in the table.
struct Lookup {
    /// The point of the unit square the VNDF warp maps to the half vector.
    sample: [f64; 2],
    vndf_pdf: f64,
    params: [f64; 2],
    u_m: [f64; 2],
    u_wi: [f64; 2],
    sin_theta_m: f64,
    wi_dot_m: f64,
}

fn bad(message: String) -> ExportError {
    ExportError::Parse {
        what: "RGL measured BSDF",
        message,
    }
}

fn field<'a>(fields: &'a [Field], name: &str) -> Result<&'a Field, ExportError> {
    fields
        .iter()
        .find(|f| f.name == name)
        .ok_or_else(|| bad(format!("no field {name:?}")))
}

/// The field's f32 values, checked for rank and finite, non-negative
/// values (a NaN or negative density would make the readers' warps
/// meaningless).
fn floats(f: &Field, rank: usize, signed: bool) -> Result<Vec<f32>, ExportError> {
    if f.dtype != Dtype::F32 || f.shape.len() != rank {
        return Err(bad(format!(
            "field {:?} must be a rank-{rank} f32 array (it is {:?} of shape {:?})",
            f.name, f.dtype, f.shape
        )));
    }
    let v = f.to_f32();
    if let Some(i) = v
        .iter()
        .position(|x| !x.is_finite() || (!signed && *x < 0.0))
    {
        return Err(bad(format!(
            "field {:?}: element {i} is {} (values must be finite{})",
            f.name,
            v[i],
            if signed { "" } else { " and non-negative" }
        )));
    }
    Ok(v)
}

fn increasing(name: &str, v: &[f32]) -> Result<Vec<f64>, ExportError> {
    if v.is_empty() || v.windows(2).any(|w| w[1] <= w[0]) {
        return Err(bad(format!(
            "field {name:?} must be non-empty and strictly increasing"
        )));
    }
    Ok(v.iter().map(|&x| x as f64).collect())
}

impl RglTable {
    /// Parses an RGL file, checking its structure as the readers do and its
    /// values beyond that (every size against the data, every density finite
    /// and non-negative, every warp slice with some mass).
    pub fn parse(bytes: &[u8]) -> Result<RglTable, ExportError> {
        let fields = tensor::read(bytes)?;
        let desc = field(&fields, "description")?;
        let jac = field(&fields, "jacobian")?;
        if desc.dtype != Dtype::U8 || desc.shape.len() != 1 {
            return Err(bad("field \"description\" must be a u8 vector".into()));
        }
        if jac.dtype != Dtype::U8 || jac.shape != [1] {
            return Err(bad("field \"jacobian\" must be one u8".into()));
        }
        let theta_i = increasing("theta_i", &floats(field(&fields, "theta_i")?, 1, true)?)?;
        let phi_i = increasing("phi_i", &floats(field(&fields, "phi_i")?, 1, true)?)?;
        let spectral = fields.iter().any(|f| f.name == "wavelengths");
        let (wavelengths, spectra_field) = if spectral {
            let w = floats(field(&fields, "wavelengths")?, 1, false)?;
            (increasing("wavelengths", &w)?, field(&fields, "spectra")?)
        } else {
            (vec![0.0, 1.0, 2.0], field(&fields, "rgb")?)
        };
        let (n_phi, n_theta) = (phi_i.len(), theta_i.len());
        let ndf_f = field(&fields, "ndf")?;
        let sigma_f = field(&fields, "sigma")?;
        let vndf_f = field(&fields, "vndf")?;
        let lum_f = field(&fields, "luminance")?;
        let ndf = floats(ndf_f, 2, false)?;
        let sigma = floats(sigma_f, 2, false)?;
        let vndf = floats(vndf_f, 4, false)?;
        let lum = floats(lum_f, 4, false)?;
        let spec = floats(spectra_field, 5, true)?;
        let (vs, ls, ss) = (&vndf_f.shape, &lum_f.shape, &spectra_field.shape);
        let ok = vs[0] == n_phi
            && vs[1] == n_theta
            && ls[0] == n_phi
            && ls[1] == n_theta
            && ls[2] == ls[3]
            && ss[0] == n_phi
            && ss[1] == n_theta
            && ss[2] == wavelengths.len()
            && ss[3] == ss[4]
            && ls[2] == ss[3];
        if !ok {
            return Err(bad(format!(
                "inconsistent shapes: phi_i {n_phi}, theta_i {n_theta}, {} wavelengths, vndf \
                 {vs:?}, luminance {ls:?}, {} {ss:?} (expected vndf [phi_i, theta_i, y, x], \
                 luminance and spectra [phi_i, theta_i, (wavelength,) n, n])",
                wavelengths.len(),
                spectra_field.name
            )));
        }
        let grid = |name: &str,
                    d: &[f32],
                    s: &[usize],
                    params: Vec<Vec<f64>>,
                    sampling: bool|
         -> Result<Marginal2D, ExportError> {
            let (h, w) = (s[s.len() - 2], s[s.len() - 1]);
            Marginal2D::new(d, w, h, params, sampling, sampling).ok_or_else(|| {
                bad(format!(
                    "field {name:?} of shape {s:?}: each 2-D slice needs at least 2 × 2 nodes{}",
                    if sampling {
                        " and some mass (a slice is all zero)"
                    } else {
                        ""
                    }
                ))
            })
        };
        let angles = vec![phi_i.clone(), theta_i.clone()];
        let mut all = angles.clone();
        all.push(wavelengths.clone());
        let reduction = if n_phi <= 2 {
            1
        } else {
            (2.0 * PI / (phi_i[n_phi - 1] - phi_i[0])).round() as i32
        };
        if ![1, 2, 4].contains(&reduction) {
            return Err(bad(format!(
                "phi_i spans 2π/{reduction}; the readers handle full, half and quarter ranges"
            )));
        }
        Ok(RglTable {
            description: String::from_utf8_lossy(&desc.bytes).into_owned(),
            isotropic: n_phi <= 2,
            reduction,
            jacobian: jac.bytes[0] != 0,
            ndf: grid("ndf", &ndf, &ndf_f.shape, vec![], false)?,
            sigma: grid("sigma", &sigma, &sigma_f.shape, vec![], false)?,
            vndf: grid("vndf", &vndf, vs, angles.clone(), true)?,
            luminance: grid("luminance", &lum, ls, angles, true)?,
            spectra: grid(&spectra_field.name, &spec, ss, all, false)?,
            shape: [ss[0], ss[1], ss[2], ss[3], ss[4]],
            theta_i,
            phi_i,
            wavelengths,
            spectral,
        })
    }

    /// The file's description text.
    pub fn description(&self) -> &str {
        &self.description
    }

    /// Whether the file is spectral (else RGB).
    pub fn is_spectral(&self) -> bool {
        self.spectral
    }

    /// Whether the file is isotropic.
    pub fn is_isotropic(&self) -> bool {
        self.isotropic
    }

    /// Tabulated wavelengths (nm), or `[0, 1, 2]` for an RGB file.
    pub fn wavelengths(&self) -> &[f64] {
        &self.wavelengths
    }

    /// Incident elevations of the table (radians).
    pub fn theta_i(&self) -> &[f64] {
        &self.theta_i
    }

    /// Incident azimuths of the table (radians).
    pub fn phi_i(&self) -> &[f64] {
        &self.phi_i
    }

    /// Shape of the spectra: φi, θi, wavelengths, and the n × n sample grid.
    pub fn shape(&self) -> [usize; 5] {
        self.shape
    }

    /// Folds the directions into the part of the azimuth range the file
    /// covers (Mitsuba's `m_reduction`): a sign flip of x and/or y.
    fn reduce(&self, wi: DVec3, wo: DVec3) -> (DVec3, DVec3) {
        if self.reduction < 2 {
            return (wi, wo);
        }
        // Mitsuba's mulsign_neg(a, s): a times the opposite of s's sign.
        let flip = |s: f64| if s >= 0.0 { -1.0 } else { 1.0 };
        let sy = flip(wi.y);
        let sx = if self.reduction == 4 { flip(wi.x) } else { sy };
        let f = |v: DVec3| DVec3::new(v.x * sx, v.y * sy, v.z);
        (f(wi), f(wo))
    }

    fn lookup(&self, wi: DVec3, wo: DVec3) -> Option<Lookup> {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return None;
        }
        let (wi, wo) = self.reduce(wi, wo);
        let m = (wi + wo).try_normalize()?;
        let (theta_i, phi_i) = (elevation(wi), wi.y.atan2(wi.x));
        let (theta_m, phi_m) = (elevation(m), m.y.atan2(m.x));
        let rel = if self.isotropic { phi_m - phi_i } else { phi_m };
        let mut u_phi = phi_to_u(rel);
        u_phi -= u_phi.floor();
        let u_m = [theta_to_u(theta_m), u_phi];
        let params = [phi_i, theta_i];
        let (sample, vndf_pdf) = self.vndf.invert(u_m, &params);
        Some(Lookup {
            sample,
            vndf_pdf,
            params,
            u_m,
            u_wi: [theta_to_u(theta_i), phi_to_u(phi_i)],
            sin_theta_m: (m.x * m.x + m.y * m.y).sqrt(),
            wi_dot_m: wi.dot(m),
        })
    }

    /// f · cosθo at `wo` for incident `wi` (local frame, both away from
    /// the surface), at `lambda` (nm; the channel 0, 1, 2 of an RGB file),
    /// as the readers compute it: spectra at the VNDF-inverted half vector,
    /// times D(m) / (4 σ(ωi)) when the file's `jacobian` flag is set,
    /// clamped at 0 as pbrt-v4 does.
    pub fn eval_cos(&self, wi: DVec3, wo: DVec3, lambda: f64) -> f64 {
        let Some(l) = self.lookup(wi, wo) else {
            return 0.0;
        };
        let s = self
            .spectra
            .eval(l.sample, &[l.params[0], l.params[1], lambda])
            .max(0.0);
        if !self.jacobian {
            return s;
        }
        let sigma = self.sigma.eval(l.u_wi, &[]);
        if sigma <= 0.0 {
            return 0.0;
        }
        s * self.ndf.eval(l.u_m, &[]) / (4.0 * sigma)
    }

    /// The BRDF f (sr⁻¹): [`RglTable::eval_cos`] / cosθo.
    pub fn eval(&self, wi: DVec3, wo: DVec3, lambda: f64) -> f64 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        self.eval_cos(wi, wo, lambda) / wo.z
    }

    /// Solid-angle density of [`RglTable::sample`] at `wo`.
    pub fn pdf(&self, wi: DVec3, wo: DVec3) -> f64 {
        let Some(l) = self.lookup(wi, wo) else {
            return 0.0;
        };
        let lum = self.luminance.eval(l.sample, &l.params);
        let jac = jacobian(l.u_m[0], l.sin_theta_m, l.wi_dot_m);
        if jac > 0.0 {
            l.vndf_pdf * lum / jac
        } else {
            0.0
        }
    }

    /// The readers' importance sampling: the luminance warp, then the VNDF
    /// warp to a half vector, reflected. `None` below the horizon.
    pub fn sample(&self, wi: DVec3, u: [f64; 2]) -> Option<TableSample> {
        if wi.z <= 0.0 {
            return None;
        }
        let (wr, _) = self.reduce(wi, wi);
        let (theta_i, phi_i) = (elevation(wr), wr.y.atan2(wr.x));
        let params = [phi_i, theta_i];
        let (s, lum_pdf) = self.luminance.sample(u, &params);
        let (u_m, vndf_pdf) = self.vndf.sample(s, &params);
        let mut phi_m = u_to_phi(u_m[1]);
        if self.isotropic {
            phi_m += phi_i;
        }
        let theta_m = u_to_theta(u_m[0]);
        let m = crate::param::direction(theta_m, phi_m);
        let wo_r = 2.0 * wr.dot(m) * m - wr;
        if wo_r.z <= 0.0 {
            return None;
        }
        let jac = jacobian(u_m[0], theta_m.sin(), wr.dot(m));
        let (_, wo) = self.reduce(wi, wo_r);
        // reduce() is an involution for a fixed wi: it maps back.
        (jac > 0.0).then_some(TableSample {
            wo,
            pdf: vndf_pdf * lum_pdf / jac,
        })
    }
}

/// dω_o / du of the reflection of the half vector at u = (u_θ, u_φ): the
/// readers' form, floored as they floor it.
fn jacobian(u_theta: f64, sin_theta_m: f64, wi_dot_m: f64) -> f64 {
    (2.0 * PI * PI * u_theta * sin_theta_m).max(1e-6) * 4.0 * wi_dot_m
}
