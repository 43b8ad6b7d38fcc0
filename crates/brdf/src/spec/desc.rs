use super::*;
use crate::wave::{Energy, FresnelAngle, PolarizationFactor};

/// `fresnel = …`: a conductor (default) or R ≡ 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FresnelKind {
    /// The measured or given n + ik (default).
    Conductor,
    /// R ≡ 1.
    #[serde(alias = "none")]
    One,
}

/// How a key is taken from an included file ([`MaterialDesc::inherit`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Group {
    /// On its own, when not set here.
    Own,
    /// With the roughness keys, only when none of them is set here.
    Roughness,
    /// With the index keys (metal, n,k), only when the index is not set here.
    Index,
    /// On its own, when neither it nor a roughness key is set here (`angle_deg`: a pair
    /// `alpha_x`, `alpha_y` set here is along the tangent axes unless turned here too).
    Orientation,
    /// Never (`include` and `cutoff` name the file and its split).
    NotInherited,
}

/// The documentation lines of a key's attributes (`///` comments), one per line.
macro_rules! doc_text {
    () => { "" };
    ([doc = $d:literal] $($rest:tt)*) => { concat!($d, "\n", doc_text!($($rest)*)) };
    ([$($other:tt)*] $($rest:tt)*) => { doc_text!($($rest)*) };
}

/// One key of [`MaterialDesc`], as [`MaterialDesc::KEY_DOCS`] lists it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KeyDoc {
    /// The key as written in a scene, a `brdf eval` line or a material file.
    pub key: &'static str,
    /// Its Rust type (`f64`, `String`, `[f64; 2]`, or an option's enum).
    pub ty: &'static str,
    /// Its documentation, one source line per line (each with a leading space).
    pub doc: &'static str,
    /// The models that read it; empty: every model (the index keys, `model`) or none
    /// but the resolution of an include.
    pub models: &'static [ModelKind],
}

/// Every key of the flat schema, listed once: its type and documentation, how it is
/// inherited from an included file, and which models read it (`[]`: every model, or
/// none but the resolution of the include). The struct, the key lists and the per-key
/// accessors are all made from this one table.
macro_rules! material_keys {
    ($( $(#[$($attr:tt)*])* $key:ident : $ty:ty, $group:ident, [$($model:ident),*]; )*) => {
        /// The flat key/value form of a material, as scene files, `brdf eval`
        /// queries and `lustre fit` material files write it (keys in the module
        /// documentation). Unknown keys are refused when deserialised.
        #[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        pub struct MaterialDesc {
            $(
                $(#[$($attr)*])*
                #[serde(default, skip_serializing_if = "Option::is_none")]
                pub $key: Option<$ty>,
            )*
        }

        impl MaterialDesc {
            /// Every key with its group and the models that read it (model parameters
            /// only: a key with no model is read by every model, or by none).
            const KEYS: &'static [(&'static str, Group, &'static [ModelKind])] = &[
                $( (stringify!($key), Group::$group, &[$(ModelKind::$model),*]), )*
            ];

            /// Every key with its type, documentation and the models that read it, in
            /// schema order (for help texts such as the Python package's).
            pub const KEY_DOCS: &'static [KeyDoc] = &[
                $( KeyDoc {
                    key: stringify!($key),
                    ty: stringify!($ty),
                    doc: doc_text!($( [$($attr)*] )*),
                    models: &[$(ModelKind::$model),*],
                }, )*
            ];

            /// Whether `key` (as written in a scene) is set.
            fn is_set(&self, key: &str) -> bool {
                match key {
                    $( stringify!($key) => self.$key.is_some(), )*
                    _ => false,
                }
            }

            /// Takes every key of `group` not set here from `base`.
            fn take(&mut self, base: &MaterialDesc, group: Group) {
                $(
                    if Group::$group == group && self.$key.is_none() {
                        self.$key = base.$key.clone();
                    }
                )*
            }
        }
    };
}

material_keys! {
    /// The reflection model.
    model: ModelKind, Own, [];
    /// A built-in metal by name (aliases as [`Metal::from_name`]).
    metal: String, Index, [];
    /// A CSV `wavelength_nm,n,k` (resolved by the caller).
    nk_csv: String, Index, [];
    /// A constant `[n, k]` (exactly two numbers).
    #[serde(deserialize_with = "exact_nk")]
    nk: [f64; 2], Index, [];
    /// `conductor` (default) or `one`.
    fresnel: FresnelKind, Index, [];
    /// Isotropic microfacet roughness.
    alpha: f64, Roughness, [Ggx, Beckmann, RoughPlastic];
    /// Roughness along the axis at `angle_deg` (the surface tangent by default).
    alpha_x: f64, Roughness, [Ggx, Beckmann];
    /// Roughness across it (the bitangent by default).
    alpha_y: f64, Roughness, [Ggx, Beckmann];
    /// Beckmann roughness, used in preference to `alpha` by `beckmann`.
    alpha_beckmann: f64, Roughness, [Beckmann];
    /// KC rms height σ, µm.
    sigma_um: f64, Own, [GhsSsa, Ghs, TwoScale, RayleighRice, GhsSsaAniso, GhsAniso];
    /// KC correlation length Lc, µm.
    lc_um: f64, Own, [GhsSsa, Ghs, TwoScale, RayleighRice];
    /// KC exponent γ.
    gamma: f64, Own, [GhsSsa, Ghs, TwoScale, RayleighRice, GhsSsaAniso, GhsAniso];
    /// GHS energy handling.
    energy: Energy, Own, [GhsSsa, Ghs, MeasuredPsd, GhsSsaAniso, GhsAniso, MeasuredPsdSsaAniso,
        MeasuredPsdAniso, MeasuredPsd2dSsa, MeasuredPsd2d];
    /// GHS Fresnel angle.
    fresnel_angle: FresnelAngle, Own, [GhsSsa, Ghs, MeasuredPsd, GhsSsaAniso, GhsAniso,
        MeasuredPsdSsaAniso, MeasuredPsdAniso, MeasuredPsd2dSsa, MeasuredPsd2d];
    /// Incident polarisation (`unpolarized`, `s`, `p`).
    polarization: Polarization, Own,
        [GhsSsa, Ghs, MeasuredPsd, RayleighRice, GhsSsaAniso, GhsAniso, MeasuredPsdSsaAniso,
        MeasuredPsdAniso, MeasuredPsd2dSsa, MeasuredPsd2d];
    /// GHS reflectance factor of the scattered part (`r` or `q`).
    polarization_factor: PolarizationFactor, Own,
        [GhsSsa, Ghs, MeasuredPsd, GhsSsaAniso, GhsAniso, MeasuredPsdSsaAniso, MeasuredPsdAniso,
        MeasuredPsd2dSsa, MeasuredPsd2d];
    /// Anisotropic correlation length along the axis, µm (the stretched measured PSD
    /// reads only Ly/Lx).
    lx_um: f64, Own, [GhsSsaAniso, GhsAniso, MeasuredPsdSsaAniso, MeasuredPsdAniso];
    /// Anisotropic correlation length across the axis, µm.
    ly_um: f64, Own, [GhsSsaAniso, GhsAniso, MeasuredPsdSsaAniso, MeasuredPsdAniso];
    /// Anisotropic axis angle (of `alpha_x`, of `lx_um`) from the tangent x towards y,
    /// degrees (default 0).
    angle_deg: f64, Orientation, [Ggx, Beckmann, GhsSsaAniso, GhsAniso, MeasuredPsdSsaAniso,
        MeasuredPsdAniso, MeasuredPsd2dSsa, MeasuredPsd2d];
    /// A CSV `zeta_rad_per_um,p_um4` (resolved by the caller; for the stretched
    /// models, the PSD of the de-stretched frame).
    psd_csv: String, Own, [MeasuredPsd, RayleighRice, MeasuredPsdSsaAniso, MeasuredPsdAniso];
    /// A measured 2-D PSD on a grid: `"[psd.map]"`, the table of an included `lustre fit`
    /// material file (the default there; resolved by the caller).
    psd_map: String, Own, [MeasuredPsd2dSsa, MeasuredPsd2d];
    /// Two-scale macro NDF width β.
    beta: f64, Own, [TwoScale];
    /// Two-scale coherent part.
    coherent: CoherentPart, Own, [TwoScale];
    /// A constant reflectance ρ ∈ [0, 1] (of a diffuse surface or base).
    reflectance: f64, Own, [Diffuse, RoughPlastic];
    /// A CSV `wavelength_nm,reflectance` (resolved by the caller).
    reflectance_csv: String, Own, [Diffuse, RoughPlastic];
    /// A checkerboard of two constant reflectances `[ρ0, ρ1]` over a shape's (u, v), as
    /// Mitsuba 3's `checkerboard` texture (ρ0 on the squares whose two indices are both
    /// even or both odd); only a scene's shapes have a (u, v): elsewhere give
    /// `reflectance`.
    #[serde(deserialize_with = "exact_checker")]
    checker_reflectance: [f64; 2], Own, [Diffuse, RoughPlastic];
    /// Squares of the checkerboard across the (u, v) unit square, `[along u, along v]`
    /// (default `[2, 2]`, Mitsuba's checkerboard).
    #[serde(deserialize_with = "exact_tiles")]
    checker_tiles: [f64; 2], Own, [Diffuse, RoughPlastic];
    /// Index of a dielectric coat (default 1.49, polypropylene).
    int_ior: f64, Own, [RoughPlastic];
    /// Index of the medium above a dielectric coat (default 1.0).
    ext_ior: f64, Own, [RoughPlastic];
    /// Whether internal scattering is tinted by the base (default false).
    nonlinear: bool, Own, [RoughPlastic];
    /// A `lustre fit` material file (resolved by the caller).
    include: String, NotInherited, [];
    /// Which two-scale split of the included file.
    cutoff: String, NotInherited, [];
}

/// `nk = [n, k]` from exactly two numbers: serde's array impl stops after
/// two and formats such as TOML do not complain about the rest, so
/// `nk = [0.2, 3.5, 9]` would otherwise pass as `[0.2, 3.5]`.
fn exact_nk<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    exact_pair(d, "an array of exactly two numbers [n, k]")
}

/// `checker_reflectance = [ρ0, ρ1]` from exactly two numbers (as `nk`).
fn exact_checker<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    exact_pair(d, "an array of exactly two reflectances [ρ0, ρ1]")
}

/// `checker_tiles = [along u, along v]` from exactly two numbers (as `nk`).
fn exact_tiles<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    exact_pair(
        d,
        "an array of exactly two square counts [along u, along v]",
    )
}

fn exact_pair<'de, D: serde::Deserializer<'de>>(
    d: D,
    what: &'static str,
) -> Result<Option<[f64; 2]>, D::Error> {
    use serde::de::{Error, IgnoredAny, SeqAccess, Visitor};
    struct Nk(&'static str);
    impl<'de> Visitor<'de> for Nk {
        type Value = [f64; 2];
        fn expecting(&self, f: &mut core::fmt::Formatter) -> core::fmt::Result {
            f.write_str(self.0)
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[f64; 2], A::Error> {
            let n = seq
                .next_element()?
                .ok_or_else(|| A::Error::invalid_length(0, &self))?;
            let k = seq
                .next_element()?
                .ok_or_else(|| A::Error::invalid_length(1, &self))?;
            let mut len = 2;
            while seq.next_element::<IgnoredAny>()?.is_some() {
                len += 1;
            }
            if len != 2 {
                return Err(A::Error::invalid_length(len, &self));
            }
            Ok([n, k])
        }
    }
    d.deserialize_seq(Nk(what)).map(Some)
}

/// Reads the files a description refers to (this crate does no I/O).
pub trait FileLoader {
    /// Rows `(λ nm, n, κ)` of an `nk_csv` file.
    fn nk_table(&mut self, path: &str) -> Result<Vec<[f64; 3]>, String>;
    /// `(ζ rad/µm, P µm⁴)` samples of a `psd_csv` file.
    fn psd_table(&mut self, path: &str) -> Result<(Vec<f64>, Vec<f64>), String>;
    /// The 2-D PSD a `psd_map` names (`angle_deg` of the result is 0, the grid's own
    /// axes). By default none: only a material file's `[psd.map]` holds one.
    fn psd_map(&mut self, path: &str) -> Result<Psd2dSpec, String> {
        Err(format!(
            "cannot read {path:?} here: a 2-D PSD comes from a `lustre fit` material file's \
             [psd.map] (include the file)"
        ))
    }
    /// Rows `(λ nm, ρ)` of a `reflectance_csv` file.
    fn reflectance_table(&mut self, path: &str) -> Result<Vec<[f64; 2]>, String>;
}

/// A loader for descriptions that must not refer to files.
pub struct NoFiles;

impl FileLoader for NoFiles {
    fn nk_table(&mut self, path: &str) -> Result<Vec<[f64; 3]>, String> {
        Err(format!(
            "cannot read {path:?} here: give `metal` or `nk` instead"
        ))
    }
    fn psd_table(&mut self, path: &str) -> Result<(Vec<f64>, Vec<f64>), String> {
        Err(format!("cannot read {path:?} here"))
    }
    fn reflectance_table(&mut self, path: &str) -> Result<Vec<[f64; 2]>, String> {
        Err(format!(
            "cannot read {path:?} here: give `reflectance` (a constant) instead"
        ))
    }
}

/// `roughplastic`'s coat index when `int_ior` is not given (polypropylene, as Mitsuba).
pub const ROUGHPLASTIC_INT_IOR: f64 = 1.49;
/// `roughplastic`'s outer index when `ext_ior` is not given.
pub const ROUGHPLASTIC_EXT_IOR: f64 = 1.0;
/// `roughplastic`'s base reflectance when neither `reflectance` nor
/// `reflectance_csv` is given (Mitsuba's default `diffuse_reflectance`).
pub const ROUGHPLASTIC_REFLECTANCE: f64 = 0.5;

/// A constant reflectance as its key; a table is left for the caller to write
/// next to the description (as an n,k table is).
fn set_reflectance(d: &mut MaterialDesc, r: &ReflectanceSpec) {
    if let ReflectanceSpec::Constant(v) = r {
        d.reflectance = Some(*v);
    }
}

fn need(v: Option<f64>, key: &'static str, model: ModelKind) -> Result<f64, SpecError> {
    v.ok_or_else(|| SpecError::new(key, format!("model `{}` needs `{key}`", model.name())))
}

/// A checkerboard material split into its two squares (see
/// [`MaterialDesc::checker_split`]).
#[derive(Clone, Debug, PartialEq)]
pub struct CheckerSquares {
    /// Squares across the (u, v) unit square, `[along u, along v]`.
    pub tiles: [f64; 2],
    /// The material of the ρ0 squares and of the ρ1 squares: this description with
    /// `reflectance = ρ0` / `ρ1` and no checker keys.
    pub squares: [MaterialDesc; 2],
}

/// Most squares a checkerboard may have along u or v: finer than any image
/// resolves, and far from where f64 loses the parity of u·tiles.
const MAX_CHECKER_TILES: f64 = 1e6;

impl MaterialDesc {
    /// The two materials of a checkerboard (`checker_reflectance`, `checker_tiles`),
    /// or `None` when the description has no checkerboard. A renderer builds both and
    /// picks one per surface point: square (i, j) = (⌊u·tiles₀⌋, ⌊v·tiles₁⌋) takes
    /// `squares[0]` when i + j is even, `squares[1]` when it is odd (Mitsuba 3's
    /// `checkerboard` spectrum with `color0`, `color1` and `to_uv` scaled by tiles/2).
    pub fn checker_split(&self) -> Result<Option<CheckerSquares>, SpecError> {
        let Some(rho) = self.checker_reflectance else {
            return match self.checker_tiles {
                None => Ok(None),
                Some(_) => Err(SpecError::new(
                    "checker_tiles",
                    "`checker_tiles` sets the squares of a `checker_reflectance = [ρ0, ρ1]` \
                     texture, which is not set: add it, or remove `checker_tiles`",
                )),
            };
        };
        if let Some(model) = self.model {
            self.check_used(model)?;
        }
        if self.reflectance.is_some() || self.reflectance_csv.is_some() {
            return Err(SpecError::new(
                "checker_reflectance",
                "give `checker_reflectance` (a checkerboard) or `reflectance`/`reflectance_csv` \
                 (one colour), not both",
            ));
        }
        for r in rho {
            if !(r.is_finite() && (0.0..=1.0).contains(&r)) {
                return Err(SpecError::new(
                    "checker_reflectance",
                    format!("each reflectance must lie in [0, 1], got {r}"),
                ));
            }
        }
        let tiles = self.checker_tiles.unwrap_or([2.0, 2.0]);
        if tiles
            .iter()
            .any(|t| !(t.is_finite() && *t > 0.0 && *t <= MAX_CHECKER_TILES))
        {
            return Err(SpecError::new(
                "checker_tiles",
                format!(
                    "each of `checker_tiles = [along u, along v]` must be a number of squares \
                     in (0, {MAX_CHECKER_TILES:e}], got [{}, {}]",
                    tiles[0], tiles[1]
                ),
            ));
        }
        let square = |r: f64| MaterialDesc {
            checker_reflectance: None,
            checker_tiles: None,
            reflectance: Some(r),
            ..self.clone()
        };
        Ok(Some(CheckerSquares {
            tiles,
            squares: [square(rho[0]), square(rho[1])],
        }))
    }

    /// Fills every key this description leaves unset from `base` (an
    /// included file): keys set here win.
    ///
    /// Keys that together describe one quantity are inherited as a group,
    /// and only when none of them is set here: the roughness (`alpha`,
    /// `alpha_x`, `alpha_y`, `alpha_beckmann`) and the index (`metal`,
    /// `nk`, `nk_csv`, `fresnel`; an explicit `fresnel = "conductor"` here
    /// still takes the index from `base`). Key by key, a fit file's `alpha_x`
    /// and `alpha_y` (or `alpha_beckmann`) would silently beat an `alpha`
    /// set here, and its `metal` would clash with an `nk` set here. The axis
    /// angle `angle_deg` is taken when neither it nor a roughness key is set
    /// here: a pair `alpha_x`, `alpha_y` set here lies along the tangent axes
    /// unless `angle_deg` is set here too, and `angle_deg` alone here turns the
    /// file's pair (and its stretched surface).
    pub fn inherit(&mut self, base: &MaterialDesc) {
        if !self.roughness_here() {
            self.take(base, Group::Roughness);
            self.take(base, Group::Orientation);
        }
        if !self.index_here() {
            self.take(base, Group::Index);
        }
        self.take(base, Group::Own);
    }

    /// Whether a roughness key is set here ([`inherit`](Self::inherit)
    /// then takes none of the base's).
    fn roughness_here(&self) -> bool {
        Self::group(Group::Roughness).any(|k| self.is_set(k))
    }

    /// The keys of `group`.
    fn group(group: Group) -> impl Iterator<Item = &'static str> {
        (Self::KEYS.iter())
            .filter(move |(_, g, _)| *g == group)
            .map(|(k, _, _)| *k)
    }

    /// Whether the index is set here ([`inherit`](Self::inherit) then
    /// takes none of the base's index keys).
    fn index_here(&self) -> bool {
        self.metal.is_some()
            || self.nk.is_some()
            || self.nk_csv.is_some()
            || self.fresnel == Some(FresnelKind::One)
    }

    /// Whether [`inherit`](Self::inherit) from `base` takes the value of
    /// `key` from `base`: `base` sets it, and this description neither
    /// sets it nor replaces its group (roughness, index). A caller that
    /// reports an invalid merged value uses it to name the file the value
    /// came from.
    pub fn inherits(&self, base: &MaterialDesc, key: &str) -> bool {
        let group = (Self::KEYS.iter())
            .find(|(k, _, _)| *k == key)
            .map(|(_, g, _)| *g);
        let replaced = match group {
            Some(Group::Roughness) => self.roughness_here(),
            Some(Group::Orientation) => self.roughness_here() || self.is_set(key),
            Some(Group::Index) => self.index_here() || self.is_set(key),
            _ => self.is_set(key),
        };
        base.is_set(key) && !replaced
    }

    /// Keys set together here of which one would silently override the
    /// other (keys inherited from an included file cannot clash with
    /// these: [`MaterialDesc::inherit`] takes each group whole).
    fn check_conflicts(&self) -> Result<(), SpecError> {
        if self.alpha.is_some() && (self.alpha_x.is_some() || self.alpha_y.is_some()) {
            let other = if self.alpha_x.is_some() {
                "alpha_x"
            } else {
                "alpha_y"
            };
            return Err(SpecError::new(
                "alpha",
                format!(
                    "`alpha` and `{other}` are both set, and `alpha_x`/`alpha_y` would win; \
                     give `alpha` (isotropic) or `alpha_x` and `alpha_y` (anisotropic), not both"
                ),
            ));
        }
        if self.fresnel == Some(FresnelKind::One) {
            let given = [
                ("metal", self.metal.is_some()),
                ("nk", self.nk.is_some()),
                ("nk_csv", self.nk_csv.is_some()),
            ];
            if let Some((key, _)) = given.iter().find(|(_, set)| *set) {
                return Err(SpecError::new(
                    "fresnel",
                    format!(
                        "`fresnel = \"one\"` (R ≡ 1) and `{key}` are both set, and `{key}` \
                         would be ignored; remove one of them"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The model parameters that are set, by name.
    fn set_keys(&self) -> Vec<&'static str> {
        (Self::KEYS.iter())
            .filter(|(k, _, models)| !models.is_empty() && self.is_set(k))
            .map(|(k, _, _)| *k)
            .collect()
    }

    /// The typed material of a description with nothing to inherit:
    /// [`MaterialDesc::resolve`] with no base.
    pub fn into_spec(&self, files: &mut dyn FileLoader) -> Result<MaterialSpec, SpecError> {
        self.resolve(None, files)
    }

    /// The typed material of this description over `base` (the
    /// `[material]` of an included `lustre fit` file, already chosen and
    /// read by the caller; keys set here win). `files` reads `nk_csv`
    /// and `psd_csv`.
    ///
    /// Every key set *here* must be one the model uses: a misspelt,
    /// misplaced or leftover key is an error naming it. Keys inherited
    /// from `base` are not checked that way, since a fit file carries α
    /// and the KC statistics for whichever model a scene picks.
    pub fn resolve(
        &self,
        base: Option<&MaterialDesc>,
        files: &mut dyn FileLoader,
    ) -> Result<MaterialSpec, SpecError> {
        self.check_conflicts()?;
        let mut merged = self.clone();
        if let Some(b) = base {
            merged.inherit(b);
        }
        merged.include = None;
        merged.cutoff = None;
        let model = merged.model.ok_or_else(|| {
            SpecError::new(
                "model",
                format!("missing `model`; one of {}", ModelKind::names()),
            )
        })?;
        self.check_used(model)?;
        self.check_index_used(model)?;
        if model == ModelKind::RayleighRice && merged.psd_csv.is_some() {
            // The table is the whole PSD (σ included): K-correlation keys set here
            // would be ignored (included ones are, as for measured_psd).
            let kc = [
                ("sigma_um", self.sigma_um.is_some()),
                ("lc_um", self.lc_um.is_some()),
                ("gamma", self.gamma.is_some()),
            ];
            if let Some((key, _)) = kc.iter().find(|(_, set)| *set) {
                return Err(SpecError::new(
                    key,
                    format!(
                        "`psd_csv` gives the whole PSD (σ included) and `{key}` would be \
                         ignored; give the table or `sigma_um`, `lc_um`, `gamma`"
                    ),
                ));
            }
        }
        if self.cutoff.is_some() && model != ModelKind::TwoScale {
            return Err(SpecError::new(
                "cutoff",
                "`cutoff` picks the split of a two_scale material's included file",
            ));
        }
        merged.build_spec(model, files)
    }

    /// The keys `model` reads (its parameters; the index keys every model reads).
    pub fn keys_of(model: ModelKind) -> Vec<&'static str> {
        (Self::KEYS.iter())
            .filter(|(_, _, models)| models.contains(&model))
            .map(|(k, _, _)| *k)
            .collect()
    }

    /// Refuses a key set here that `model` does not read.
    pub fn check_used(&self, model: ModelKind) -> Result<(), SpecError> {
        let used = Self::keys_of(model);
        match self.set_keys().into_iter().find(|k| !used.contains(k)) {
            None => Ok(()),
            Some(extra) => Err(SpecError::new(
                extra,
                format!(
                    "model `{}` does not use `{extra}`; its parameters are: {}",
                    model.name(),
                    if used.is_empty() {
                        "none".to_string()
                    } else {
                        used.join(", ")
                    }
                ),
            )),
        }
    }

    /// Refuses a conductor index (`metal`, `nk`, `nk_csv`, `fresnel`) set here
    /// on a model without a conductor Fresnel term (one inherited from an
    /// included fit file is ignored, as its other unused keys are).
    fn check_index_used(&self, model: ModelKind) -> Result<(), SpecError> {
        if model.conductor() {
            return Ok(());
        }
        let given = [
            ("metal", self.metal.is_some()),
            ("nk", self.nk.is_some()),
            ("nk_csv", self.nk_csv.is_some()),
            ("fresnel", self.fresnel.is_some()),
        ];
        match given.iter().find(|(_, set)| *set) {
            None => Ok(()),
            Some((key, _)) => Err(SpecError::new(
                key,
                format!(
                    "model `{}` has no conductor Fresnel term, so `{key}` would be ignored; \
                     its colour is `reflectance = ρ` or `reflectance_csv = \"file.csv\"`{}",
                    model.name(),
                    if model == ModelKind::RoughPlastic {
                        " and its coat's Fresnel term comes from `int_ior` and `ext_ior`"
                    } else {
                        ""
                    }
                ),
            )),
        }
    }

    /// The reflectance of a diffuse surface or base: `reflectance` or
    /// `reflectance_csv` (exactly one; `default` when neither is set).
    fn reflectance_spec(
        &self,
        model: ModelKind,
        default: Option<f64>,
        files: &mut dyn FileLoader,
    ) -> Result<ReflectanceSpec, SpecError> {
        if self.checker_reflectance.is_some() || self.checker_tiles.is_some() {
            return Err(SpecError::new(
                "checker_reflectance",
                "a checkerboard varies over a shape's surface, so only a scene's shapes read \
                 `checker_reflectance`/`checker_tiles` (through `MaterialDesc::checker_split`); \
                 here, with no surface position, give `reflectance = ρ`",
            ));
        }
        match (self.reflectance, &self.reflectance_csv) {
            (Some(_), Some(_)) => Err(SpecError::new(
                "reflectance",
                "give `reflectance` (a constant) or `reflectance_csv` (a spectrum), not both",
            )),
            (Some(r), None) => {
                Reflectance::constant(r)?;
                Ok(ReflectanceSpec::Constant(r))
            }
            (None, Some(path)) => {
                let rows = files
                    .reflectance_table(path)
                    .map_err(|e| SpecError::new("reflectance_csv", e))?;
                Reflectance::table(rows.clone())
                    .map_err(|e| SpecError::new("reflectance_csv", format!("{path}: {e}")))?;
                Ok(ReflectanceSpec::Table(rows))
            }
            (None, None) => default.map(ReflectanceSpec::Constant).ok_or_else(|| {
                SpecError::new(
                    "reflectance",
                    format!(
                        "model `{}` needs `reflectance = ρ` (0 ≤ ρ ≤ 1) or \
                         `reflectance_csv = \"file.csv\"` (wavelength_nm,reflectance)",
                        model.name()
                    ),
                )
            }),
        }
    }

    fn build_spec(
        &self,
        model: ModelKind,
        files: &mut dyn FileLoader,
    ) -> Result<MaterialSpec, SpecError> {
        let fresnel = if model.conductor() {
            self.fresnel_spec(files)?
        } else {
            FresnelSpec::One
        };
        let kc = |m| -> Result<KcSpec, SpecError> {
            Ok(KcSpec {
                sigma_um: need(self.sigma_um, "sigma_um", m)?,
                lc_um: need(self.lc_um, "lc_um", m)?,
                gamma: need(self.gamma, "gamma", m)?,
            })
        };
        let options = GhsOptions {
            energy: self.energy.unwrap_or_default(),
            fresnel_angle: self.fresnel_angle.unwrap_or_default(),
            polarization: self.polarization.unwrap_or_default(),
            polarization_factor: self.polarization_factor.unwrap_or_default(),
        };
        let aniso = |m| -> Result<AnisoSpec, SpecError> {
            Ok(AnisoSpec {
                sigma_um: need(self.sigma_um, "sigma_um", m)?,
                lx_um: need(self.lx_um, "lx_um", m)?,
                ly_um: need(self.ly_um, "ly_um", m)?,
                angle_deg: self.angle_deg.unwrap_or(0.0),
                gamma: need(self.gamma, "gamma", m)?,
            })
        };
        let spec = match model {
            ModelKind::Ggx => {
                let (alpha_x, alpha_y) = self.roughness(model, self.alpha)?;
                ModelSpec::Ggx {
                    alpha_x,
                    alpha_y,
                    angle_deg: self.angle_deg.unwrap_or(0.0),
                }
            }
            ModelKind::Beckmann => {
                let (alpha_x, alpha_y) =
                    self.roughness(model, self.alpha_beckmann.or(self.alpha))?;
                ModelSpec::Beckmann {
                    alpha_x,
                    alpha_y,
                    angle_deg: self.angle_deg.unwrap_or(0.0),
                }
            }
            ModelKind::Smooth => ModelSpec::Smooth,
            ModelKind::GhsSsa => ModelSpec::GhsSsa {
                surface: kc(model)?,
                options,
            },
            ModelKind::Ghs => ModelSpec::Ghs {
                surface: kc(model)?,
                options,
            },
            ModelKind::MeasuredPsd => {
                let (zeta_rad_per_um, psd_um4) = self.psd_of(model, files)?;
                ModelSpec::MeasuredPsd {
                    zeta_rad_per_um,
                    psd_um4,
                    options,
                }
            }
            ModelKind::TwoScale => ModelSpec::TwoScale {
                beta: need(self.beta, "beta", model)?,
                surface: kc(model)?,
                coherent: self.coherent.unwrap_or_default(),
            },
            ModelKind::RayleighRice => {
                let surface = match self.psd_csv.as_deref() {
                    Some(path) => {
                        let (zeta_rad_per_um, psd_um4) = files
                            .psd_table(path)
                            .map_err(|e| SpecError::new("psd_csv", e))?;
                        RrSurface::Measured {
                            zeta_rad_per_um,
                            psd_um4,
                        }
                    }
                    None => RrSurface::Kc(kc(model)?),
                };
                ModelSpec::RayleighRice {
                    surface,
                    polarization: options.polarization,
                }
            }
            ModelKind::GhsSsaAniso => ModelSpec::GhsSsaAniso {
                surface: aniso(model)?,
                options,
            },
            ModelKind::GhsAniso => ModelSpec::GhsAniso {
                surface: aniso(model)?,
                options,
            },
            ModelKind::MeasuredPsdSsaAniso => ModelSpec::MeasuredPsdSsaAniso {
                surface: self.measured_aniso(model, files)?,
                options,
            },
            ModelKind::MeasuredPsdAniso => ModelSpec::MeasuredPsdAniso {
                surface: self.measured_aniso(model, files)?,
                options,
            },
            ModelKind::MeasuredPsd2dSsa | ModelKind::MeasuredPsd2d => {
                let path = self.psd_map.as_deref().ok_or_else(|| {
                    SpecError::new(
                        "psd_map",
                        format!(
                            "model `{}` needs a 2-D PSD: include a `lustre fit` material file \
                             with a [psd.map] table (written for maps whose 2-D PSD is not \
                             elliptical)",
                            model.name()
                        ),
                    )
                })?;
                let mut surface = files
                    .psd_map(path)
                    .map_err(|e| SpecError::new("psd_map", e))?;
                surface.angle_deg = self.angle_deg.unwrap_or(0.0);
                if model == ModelKind::MeasuredPsd2d {
                    ModelSpec::MeasuredPsd2d { surface, options }
                } else {
                    ModelSpec::MeasuredPsd2dSsa { surface, options }
                }
            }
            ModelKind::Diffuse => ModelSpec::Diffuse {
                reflectance: self.reflectance_spec(model, None, files)?,
            },
            ModelKind::RoughPlastic => ModelSpec::RoughPlastic {
                alpha: need(self.alpha, "alpha", model)?,
                int_ior: self.int_ior.unwrap_or(ROUGHPLASTIC_INT_IOR),
                ext_ior: self.ext_ior.unwrap_or(ROUGHPLASTIC_EXT_IOR),
                reflectance: self.reflectance_spec(model, Some(ROUGHPLASTIC_REFLECTANCE), files)?,
                nonlinear: self.nonlinear.unwrap_or(false),
            },
        };
        let spec = MaterialSpec {
            model: spec,
            fresnel,
        };
        spec.validate()?;
        Ok(spec)
    }

    /// The `psd_csv` table of a measured-PSD model.
    fn psd_of(
        &self,
        model: ModelKind,
        files: &mut dyn FileLoader,
    ) -> Result<(Vec<f64>, Vec<f64>), SpecError> {
        let path = self.psd_csv.as_deref().ok_or_else(|| {
            SpecError::new(
                "psd_csv",
                format!(
                    "model `{}` needs `psd_csv = \"file.csv\"` (zeta_rad_per_um,p_um4) or an \
                     included fit file with a [psd] table",
                    model.name()
                ),
            )
        })?;
        files
            .psd_table(path)
            .map_err(|e| SpecError::new("psd_csv", e))
    }

    /// The surface of the stretched measured-PSD models.
    fn measured_aniso(
        &self,
        model: ModelKind,
        files: &mut dyn FileLoader,
    ) -> Result<MeasuredAnisoSpec, SpecError> {
        let (zeta_rad_per_um, psd_um4) = self.psd_of(model, files)?;
        Ok(MeasuredAnisoSpec {
            zeta_rad_per_um,
            psd_um4,
            lx_um: need(self.lx_um, "lx_um", model)?,
            ly_um: need(self.ly_um, "ly_um", model)?,
            angle_deg: self.angle_deg.unwrap_or(0.0),
        })
    }

    fn roughness(&self, model: ModelKind, iso: Option<f64>) -> Result<(f64, f64), SpecError> {
        match (self.alpha_x, self.alpha_y, iso) {
            (Some(x), Some(y), _) => Ok((x, y)),
            (None, None, Some(a)) => Ok((a, a)),
            (Some(_), None, _) => Err(SpecError::new(
                "alpha_y",
                "give both `alpha_x` and `alpha_y`",
            )),
            (None, Some(_), _) => Err(SpecError::new(
                "alpha_x",
                "give both `alpha_x` and `alpha_y`",
            )),
            (None, None, None) => Err(SpecError::new(
                "alpha",
                format!(
                    "model `{}` needs `alpha` (or `alpha_x` and `alpha_y`)",
                    model.name()
                ),
            )),
        }
    }

    fn fresnel_spec(&self, files: &mut dyn FileLoader) -> Result<FresnelSpec, SpecError> {
        if self.fresnel == Some(FresnelKind::One) {
            return Ok(FresnelSpec::One);
        }
        let given = [
            self.metal.is_some(),
            self.nk_csv.is_some(),
            self.nk.is_some(),
        ];
        match given.iter().filter(|&&g| g).count() {
            0 => Err(SpecError::new(
                "metal",
                "needs one of `metal = \"NAME\"`, `nk_csv = \"file.csv\"`, `nk = [n, k]` \
                 (or `fresnel = \"one\"` for R ≡ 1)",
            )),
            1 => {
                if let Some(name) = &self.metal {
                    let m = Metal::from_name(name).ok_or_else(|| {
                        let names: Vec<&str> = Metal::ALL.iter().map(|m| m.name()).collect();
                        SpecError::new(
                            "metal",
                            format!("unknown metal `{name}`; valid: {}", names.join(", ")),
                        )
                    })?;
                    Ok(FresnelSpec::Metal(m))
                } else if let Some(path) = &self.nk_csv {
                    let rows = files
                        .nk_table(path)
                        .map_err(|e| SpecError::new("nk_csv", e))?;
                    Ior::table(rows.clone())
                        .map_err(|e| SpecError::new("nk_csv", e.to_string()))?;
                    Ok(FresnelSpec::Table(rows))
                } else {
                    let [n, k] = self.nk.unwrap_or_default();
                    Ior::constant(n, k).map_err(|e| SpecError::new("nk", e.to_string()))?;
                    Ok(FresnelSpec::Constant { n, k })
                }
            }
            _ => Err(SpecError::new(
                "metal",
                "give only one of `metal`, `nk_csv`, `nk`",
            )),
        }
    }
}

impl MaterialSpec {
    /// The flat form. Tabulated data (a measured PSD, an n,k table, a
    /// reflectance spectrum) is not representable as keys: `psd_csv` /
    /// `nk_csv` / `reflectance_csv` are left unset and the caller writes the
    /// data next to the description.
    pub fn to_desc(&self) -> MaterialDesc {
        let mut d = MaterialDesc {
            model: Some(self.model.kind()),
            ..MaterialDesc::default()
        };
        match &self.fresnel {
            // Implied by the models without a conductor Fresnel term.
            FresnelSpec::One if !self.model.kind().conductor() => {}
            FresnelSpec::One => d.fresnel = Some(FresnelKind::One),
            FresnelSpec::Metal(m) => d.metal = Some(m.name().to_string()),
            FresnelSpec::Constant { n, k } => d.nk = Some([*n, *k]),
            FresnelSpec::Table(_) => {}
        }
        let set_kc = |d: &mut MaterialDesc, s: &KcSpec| {
            d.sigma_um = Some(s.sigma_um);
            d.lc_um = Some(s.lc_um);
            d.gamma = Some(s.gamma);
        };
        let set_opts = |d: &mut MaterialDesc, o: &GhsOptions| {
            d.energy = Some(o.energy);
            d.fresnel_angle = Some(o.fresnel_angle);
            // The scalar theory's defaults are left implicit, as files written
            // before the polarisation options have them.
            let defaults = GhsOptions::default();
            d.polarization = (o.polarization != defaults.polarization).then_some(o.polarization);
            d.polarization_factor = (o.polarization_factor != defaults.polarization_factor)
                .then_some(o.polarization_factor);
        };
        match &self.model {
            ModelSpec::Ggx {
                alpha_x,
                alpha_y,
                angle_deg,
            }
            | ModelSpec::Beckmann {
                alpha_x,
                alpha_y,
                angle_deg,
            } => {
                if alpha_x == alpha_y {
                    d.alpha = Some(*alpha_x);
                } else {
                    d.alpha_x = Some(*alpha_x);
                    d.alpha_y = Some(*alpha_y);
                }
                // Absent at 0, as a material written before the key has it.
                d.angle_deg = (*angle_deg != 0.0).then_some(*angle_deg);
            }
            ModelSpec::Smooth => {}
            ModelSpec::GhsSsa { surface, options } | ModelSpec::Ghs { surface, options } => {
                set_kc(&mut d, surface);
                set_opts(&mut d, options);
            }
            ModelSpec::MeasuredPsd { options, .. } => set_opts(&mut d, options),
            ModelSpec::TwoScale {
                beta,
                surface,
                coherent,
            } => {
                d.beta = Some(*beta);
                set_kc(&mut d, surface);
                d.coherent = Some(*coherent);
            }
            ModelSpec::RayleighRice {
                surface,
                polarization,
            } => {
                if let RrSurface::Kc(kc) = surface {
                    set_kc(&mut d, kc);
                }
                d.polarization = Some(*polarization);
            }
            ModelSpec::GhsSsaAniso { surface, options }
            | ModelSpec::GhsAniso { surface, options } => {
                d.sigma_um = Some(surface.sigma_um);
                d.lx_um = Some(surface.lx_um);
                d.ly_um = Some(surface.ly_um);
                d.angle_deg = Some(surface.angle_deg);
                d.gamma = Some(surface.gamma);
                set_opts(&mut d, options);
            }
            ModelSpec::MeasuredPsdSsaAniso { surface, options }
            | ModelSpec::MeasuredPsdAniso { surface, options } => {
                d.lx_um = Some(surface.lx_um);
                d.ly_um = Some(surface.ly_um);
                d.angle_deg = Some(surface.angle_deg);
                set_opts(&mut d, options);
            }
            ModelSpec::MeasuredPsd2dSsa { surface, options }
            | ModelSpec::MeasuredPsd2d { surface, options } => {
                d.angle_deg = Some(surface.angle_deg);
                set_opts(&mut d, options);
            }
            ModelSpec::Diffuse { reflectance } => set_reflectance(&mut d, reflectance),
            ModelSpec::RoughPlastic {
                alpha,
                int_ior,
                ext_ior,
                reflectance,
                nonlinear,
            } => {
                d.alpha = Some(*alpha);
                d.int_ior = Some(*int_ior);
                d.ext_ior = Some(*ext_ior);
                set_reflectance(&mut d, reflectance);
                d.nonlinear = Some(*nonlinear);
            }
        }
        d
    }
}

#[cfg(test)]
mod key_doc_tests {
    use super::*;

    /// The documented table is the schema: the same keys in the same order, each
    /// documented, each accepted by the deserialiser under that name and with those models.
    #[test]
    fn key_docs_list_every_key_of_the_schema() {
        let docs = MaterialDesc::KEY_DOCS;
        assert_eq!(docs.len(), MaterialDesc::KEYS.len());
        for (d, (k, _, models)) in docs.iter().zip(MaterialDesc::KEYS) {
            assert_eq!(d.key, *k);
            assert_eq!(d.models, *models);
            assert!(!d.doc.trim().is_empty(), "{k} has no documentation");
            assert!(!d.doc.contains("serde"), "{k}: {}", d.doc);
            let one = serde_json::json!({ (d.key): serde_json::Value::Null });
            let err = serde_json::from_value::<MaterialDesc>(one)
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default();
            assert!(!err.contains("unknown field"), "{k}: {err}");
        }
        let nk = docs.iter().find(|d| d.key == "nk").unwrap();
        assert_eq!(nk.ty, "[f64; 2]");
        assert_eq!(nk.doc, " A constant `[n, k]` (exactly two numbers).\n");
    }
}
