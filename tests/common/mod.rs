//! What several end-to-end tests share.

/// The smallest scene that renders: a 4×3 GGX brass plate under a point light, 1 spp.
pub const TINY_SCENE: &str = r#"[camera]
look_from = [0.0, 1.0, 2.0]
look_at = [0.0, 0.0, 0.0]
fov_deg = 40.0
resolution = [4, 3]

[film]
spp = 1

[materials.m]
model = "ggx"
metal = "brass"
alpha = 0.2

[[shapes]]
type = "rectangle"
size = [1.0, 1.0]
material = "m"
transform = { rotate_deg = [-90.0, 0.0, 0.0] }

[[lights]]
type = "point"
position = [0.0, 1.0, 0.0]
intensity = 1.0
"#;
