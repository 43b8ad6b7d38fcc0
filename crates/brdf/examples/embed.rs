//! How another renderer embeds `brdf`: build a copper GGX material once,
//! then, per shading point, move directions into the local frame, evaluate
//! (light sampling), sample (BSDF sampling), and handle a delta lobe through
//! `specular()` generically, for any model behind `&dyn Bxdf`.
//!
//! Run: `cargo run -p brdf --example embed`.

use brdf::frame::orthonormal_basis;
use brdf::microfacet::{Distribution, MicrofacetConductor};
use brdf::{BrdfError, Bxdf, DVec3, Fresnel, Ior, Metal, SmoothConductor};

/// The renderer's shading frame: world ↔ local (normal = +z).
struct Frame {
    t: DVec3,
    b: DVec3,
    n: DVec3,
}

impl Frame {
    fn new(n: DVec3) -> Frame {
        let (t, b) = orthonormal_basis(n);
        Frame { t, b, n }
    }
    fn to_local(&self, w: DVec3) -> DVec3 {
        DVec3::new(w.dot(self.t), w.dot(self.b), w.dot(self.n))
    }
    fn to_world(&self, w: DVec3) -> DVec3 {
        self.t * w.x + self.b * w.y + self.n * w.z
    }
}

/// Stand-in for the renderer's sampler.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// One bounce of a path tracer at one wavelength: next-event estimation
/// towards a point light, then a continuation direction from the BSDF. Works
/// for glossy, delta and mixed models alike.
fn shade(
    bxdf: &dyn Bxdf,
    frame: &Frame,
    to_eye: DVec3,
    to_light: DVec3,
    lambda: f64,
    rng: &mut Lcg,
) {
    let wi = frame.to_local(to_eye);
    let wl = frame.to_local(to_light);
    // Light sampling: f · cosθ; the BSDF pdf would weight MIS against it.
    let f = bxdf.eval(wi, wl, lambda);
    let pdf = bxdf.pdf(wi, wl, lambda);
    println!(
        "  λ = {lambda:.0} nm: f·cos toward light = {:.4} (BSDF pdf there {pdf:.4})",
        f * wl.z.max(0.0)
    );

    // The delta lobe is never hit by light sampling; the renderer adds it by
    // following the mirror direction with weight `specular.weight`.
    let spec = bxdf.specular(wi, lambda);
    if spec.weight > 0.0 {
        println!(
            "  delta lobe: weight {:.4}, sampled with probability {:.2}",
            spec.weight, spec.probability
        );
    }

    // BSDF sampling: throughput *= weight; `is_delta` tells MIS to skip the light pdf.
    match bxdf.sample(wi, lambda, [rng.next(), rng.next(), rng.next()]) {
        Some(s) => {
            let world = frame.to_world(s.wo);
            println!(
                "  sampled wo (world) = ({:.3}, {:.3}, {:.3}), weight {:.4}, pdf {:.3}, delta: {}",
                world.x, world.y, world.z, s.weight, s.pdf, s.is_delta
            );
        }
        None => println!("  sample carried no energy (path ends)"),
    }
}

fn main() -> Result<(), BrdfError> {
    // Materials are validated once, when built; evaluation never fails.
    let copper = MicrofacetConductor::new(
        Distribution::ggx(0.15, 0.15)?,
        Fresnel::conductor(Ior::metal(Metal::Cu)),
    )?;
    let brushed = MicrofacetConductor::new(
        Distribution::ggx(0.05, 0.3)?,
        Fresnel::conductor(Ior::metal(Metal::Al)),
    )?;
    let mirror = SmoothConductor::new(Fresnel::conductor(Ior::metal(Metal::Ag)))?;

    // A tilted surface point with eye and light in world space.
    let frame = Frame::new(DVec3::new(0.2, 0.1, 1.0).normalize());
    let to_eye = DVec3::new(-0.6, 0.0, 0.8).normalize();
    let to_light = DVec3::new(0.7, 0.1, 0.7).normalize();
    let mut rng = Lcg(1);

    let materials: [(&str, &dyn Bxdf); 3] = [
        ("copper GGX α = 0.15", &copper),
        ("brushed Al GGX α = (0.05, 0.3)", &brushed),
        ("smooth silver", &mirror),
    ];
    for (name, bxdf) in materials {
        println!("{name}:");
        for lambda in [450.0, 550.0, 650.0] {
            shade(bxdf, &frame, to_eye, to_light, lambda, &mut rng);
        }
    }

    // Bad parameters are reported, naming the parameter and its valid range.
    if let Err(e) = Distribution::ggx(0.0, 0.2) {
        println!("rejected: {e}");
    }
    let short = Ior::table(vec![[400.0, 0.3, 3.0], [700.0, 0.2, 4.0]])?;
    if let Err(e) =
        MicrofacetConductor::new(Distribution::beckmann(0.2, 0.2)?, Fresnel::conductor(short))
    {
        println!("rejected: {e}");
    }
    Ok(())
}
