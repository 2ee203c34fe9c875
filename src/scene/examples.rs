//! Built-in example scenes (`dfem example NAME`): one per generator, plus a wall with a
//! window and a door. Each is small (under 300 blocks) and runs a static analysis.

/// (name, one-line description, TOML text)
pub const EXAMPLES: &[(&str, &str, &str)] = &[
    ("incline", "one block on a 30 degree incline, phi = 20 degrees: it slides (Hoek and Bray; seed section 4.1)", INCLINE),
    ("wall", "a dry-joint running-bond brick wall, 10 courses of 5 bricks, on a fixed base", WALL),
    ("wall-window", "a running-bond brick wall 4 m x 2.4 m with a window and a door", WALL_WINDOW),
    ("arch", "a semicircular arch of 13 voussoirs on two piers (seed section 4.3, Table 2 properties)", ARCH),
    ("tower", "a masonry tower section 2 m x 8 m, 16 courses, with a door", TOWER),
    ("column", "a multi-drum column: six marble drums 0.8 m x 1.0 m, deformable, meshed at 0.05 m, under 0.1 g lateral (stands; rocks at b/H = 0.133)", COLUMN),
    ("slope", "the Goodman and Bray (1976) toppling rock slope: 16 columns on a stepped base", SLOPE),
    ("sliding", "dynamic: a 4 m x 4 m block slides down a 30 degree incline, phi = 25 degrees (seed section 4.2, dt = 0.04 s)", SLIDING),
    ("tunnel", "a circular tunnel in rock cut by two joint sets, inside a fixed frame", TUNNEL),
    ("eindhoven", "the Eindhoven shear wall J4D/J5D (Raijmakers and Vermeltfoort 1992): softening joints with a cap, split bricks, 0.30 N/mm2 pre-compression, top pushed 4 mm held horizontal, dissipation-based arc length", EINDHOVEN),
    ("eindhoven-j6d", "the Eindhoven shear wall J6D: as eindhoven, 1.21 N/mm2 pre-compression", EINDHOVEN_J6D),
    ("eindhoven-j7d", "the Eindhoven shear wall J7D: as eindhoven, 2.12 N/mm2 pre-compression", EINDHOVEN_J7D),
];

pub fn get(name: &str) -> Option<&'static str> {
    EXAMPLES.iter().find(|e| e.0 == name).map(|e| e.2)
}

/// The `wall` example with `n` courses of `n` bricks (0.4 m × 0.2 m), deformable bricks
/// meshed by their corners and contact nodes (about 12 unknowns each) or rigid ones (3
/// each): the scalable model of the solver benchmarks and tests.
pub fn scaled_wall(n: usize, rigid: bool) -> String {
    let kind = if rigid { "\nkind = \"rigid\"" } else { "" };
    WALL.replace("courses = 10", &format!("courses = {n}"))
        .replace(
            "bricks_per_course = 5",
            &format!("bricks_per_course = {n}{kind}"),
        )
}

const COLUMN: &str = r#"title = "Multi-drum column: six marble drums on a fixed base, 0.1 g lateral"
# Six drums 0.8 m wide and 1.0 m high (a column 6 m high, b/H = 0.133), deformable marble
# meshed at 0.05 m, dry joints (phi = 35 degrees, no cohesion or tension). The contacts act
# on the drums' top and bottom faces only, so 92 % of the unknowns are the drums'
# interiors, which the default solver condenses out (docs/solvers.md, "Static
# condensation"). Under 0.1 g the column stands, its joints opening on the windward side;
# as a rigid stack it would rock about the bottom joint's toe at lambda = b/H = 0.133
# (`type = "capacity"` gives 0.1330).

[model]
plane = "strain"
thickness = 1.0
gravity = [0.0, -9.81]

[[material]]
name = "marble"
lame_lambda = 1.389e10
lame_mu = 2.083e10
unit_weight = 27e3

[[joint]]
name = "dry"
normal_modulus = 5e10
shear_modulus = 2e10
band = 0.010
friction_angle = 35.0

[[block]]
name = "base"
material = "marble"
support = "fixed"
vertices = [[-0.6, -0.4], [1.4, -0.4], [1.4, 0.0], [-0.6, 0.0]]

[[block]]
name = "d1"
material = "marble"
mesh_size = 0.05
vertices = [[0.0, 0.0], [0.8, 0.0], [0.8, 1.0], [0.0, 1.0]]

[[block]]
name = "d2"
material = "marble"
mesh_size = 0.05
vertices = [[0.0, 1.0], [0.8, 1.0], [0.8, 2.0], [0.0, 2.0]]

[[block]]
name = "d3"
material = "marble"
mesh_size = 0.05
vertices = [[0.0, 2.0], [0.8, 2.0], [0.8, 3.0], [0.0, 3.0]]

[[block]]
name = "d4"
material = "marble"
mesh_size = 0.05
vertices = [[0.0, 3.0], [0.8, 3.0], [0.8, 4.0], [0.0, 4.0]]

[[block]]
name = "d5"
material = "marble"
mesh_size = 0.05
vertices = [[0.0, 4.0], [0.8, 4.0], [0.8, 5.0], [0.0, 5.0]]

[[block]]
name = "d6"
material = "marble"
mesh_size = 0.05
vertices = [[0.0, 5.0], [0.8, 5.0], [0.8, 6.0], [0.0, 6.0]]

[contacts]
joint = "dry"

[analysis]
type = "static"
lateral = 0.1
load_steps = 5
gravity_steps = 1
"#;

/// The `column` example with its drums meshed at `mesh` m and `analysis` (a whole
/// `[analysis]` table) instead of its own: the model of tests/condensation.rs and of the
/// condensation bench.
pub fn drum_column(mesh: f64, analysis: &str) -> String {
    let head = COLUMN
        .split("[analysis]")
        .next()
        .expect("the example has an analysis");
    format!(
        "{}{analysis}",
        head.replace("mesh_size = 0.05", &format!("mesh_size = {mesh}"))
    )
}

const INCLINE: &str = r#"title = "One block on a 30 degree incline (Hoek and Bray 1977; seed section 4.1)"
# alpha = 30 > phi = 20 and b/d = 1 > tan(alpha): the block slides.

[model]
plane = "strain"
thickness = 1.0
gravity = [0.0, -9.81]

[[material]]
name = "rock"
lame_lambda = 56e9
lame_mu = 21e9
unit_weight = 25e3

[[joint]]
name = "rock-rock"
normal_modulus = 50e9
shear_modulus = 0.5e9
band = 0.010
friction_angle = 20.0

[[generate]]
type = "incline"
material = "rock"
slope_angle = 30.0
breadth = 1.0
height = 1.0

[contacts]
joint = "rock-rock"
tolerance = 1e-6

[analysis]
type = "static"
"#;

const SLIDING: &str = r#"title = "A block sliding down a 30 degree incline, dynamic (seed section 4.2)"
# alpha = 30 > phi = 25 and b/d = 1 > tan(alpha): the block slides; from rest,
# s(t) = g (sin 30 - cos 30 tan 25) t^2 / 2 = 1.89 m at t = 2 s.

[[material]]
name = "rock"
lame_lambda = 56e9
lame_mu = 21e9
unit_weight = 25e3

[[joint]]
name = "rock-rock"
normal_modulus = 50e9
shear_modulus = 0.5e9
band = 0.010
friction_angle = 25.0

[[generate]]
type = "incline"
material = "rock"
slope_angle = 30.0
breadth = 4.0
height = 4.0
slope_length = 24.0

[contacts]
joint = "rock-rock"

[analysis]
type = "dynamic"
dt = 0.04
duration = 2.0
integrator = "hht"

[output]
every = 5
"#;

const WALL: &str = r#"title = "Running-bond brick wall on a fixed base"
# Bricks 0.4 m x 0.2 m (joint thickness included, Lourenco's simplified micro-model),
# E = 5 GPa, nu = 0.2; joint stiffness kn = 82 N/mm3, ks = 36 N/mm3 over a 10 mm band.

[model]
plane = "stress"
thickness = 0.1
gravity = [0.0, -9.81]

[[material]]
name = "brick"
lame_lambda = 1.389e9
lame_mu = 2.083e9
unit_weight = 18e3

[[joint]]
name = "dry-joint"
normal_modulus = 8.2e8
shear_modulus = 3.6e8
band = 0.010
friction_angle = 36.87
cohesion = 0.0

[[generate]]
type = "wall"
material = "brick"
courses = 10
bricks_per_course = 5
brick_length = 0.4
brick_height = 0.2
joint = 0.0

[contacts]
joint = "dry-joint"
tolerance = 1e-6

[analysis]
type = "static"
"#;

const WALL_WINDOW: &str = r#"title = "Brick wall with a window and a door"
# 12 courses of 10 bricks 0.4 m x 0.2 m: 4.0 m x 2.4 m. The window (1.0 m x 0.8 m) and the
# door (0.8 m x 2.0 m) cut the bricks they cross; bricks wholly inside are removed.
# The top beam ties the wall above the openings.

[model]
plane = "stress"
thickness = 0.1
gravity = [0.0, -9.81]

[[material]]
name = "brick"
lame_lambda = 1.389e9
lame_mu = 2.083e9
unit_weight = 18e3

[[joint]]
name = "mortar"
normal_modulus = 8.2e8
shear_modulus = 3.6e8
band = 0.010
friction_angle = 36.87
cohesion = 0.35e6
tensile_strength = 0.25e6

[[generate]]
type = "wall"
material = "brick"
courses = 12
bricks_per_course = 10
brick_length = 0.4
brick_height = 0.2
top_beam = true
openings = [
  { x = 0.5, y = 1.1, width = 1.0, height = 0.8 },   # window
  { x = 2.6, y = 0.0, width = 0.8, height = 2.0 },   # door
]

[contacts]
joint = "mortar"
tolerance = 1e-6

[analysis]
type = "static"
"#;

const ARCH: &str = r#"title = "Semicircular masonry arch on two piers (seed section 4.3, Table 2)"
# Span 4 m, 13 voussoirs 0.4 m thick; piers 2 m high in 4 courses on a fixed base.

[model]
plane = "strain"
thickness = 1.0
gravity = [0.0, -9.81]

[[material]]
name = "masonry"
lame_lambda = 30e6
lame_mu = 30e6
viscous_lambda = 30e6
viscous_mu = 30e6
unit_weight = 25e3

[[joint]]
name = "masonry-joint"
normal_modulus = 50e6
shear_modulus = 25e6
normal_viscosity = 5e6
shear_viscosity = 2.5e6
band = 0.005
friction_angle = 35.0

[[generate]]
type = "arch"
material = "masonry"
shape = "semicircular"
span = 4.0
thickness = 0.4
voussoirs = 13
pier_height = 2.0
pier_courses = 4
# piers 1 m wide: with 0.4 m piers 2 m tall the thrust overturns them under self-weight
pier_width = 1.0

[contacts]
joint = "masonry-joint"
tolerance = 1e-6

[analysis]
type = "static"
"#;

const TOWER: &str = r#"title = "Masonry tower section with a door"
# 2 m wide, 8 m high, 16 courses of 2 stones (running bond), stone masonry E = 5 GPa.

[model]
plane = "stress"
thickness = 1.0
gravity = [0.0, -9.81]

[[material]]
name = "stone"
lame_lambda = 1.389e9
lame_mu = 2.083e9
unit_weight = 22e3

[[joint]]
name = "stone-joint"
normal_modulus = 2e9
shear_modulus = 0.8e9
band = 0.010
friction_angle = 35.0

[[generate]]
type = "tower"
material = "stone"
width = 2.0
height = 8.0
courses = 16
blocks_per_course = 2
openings = [{ x = 0.6, y = 0.0, width = 0.8, height = 2.0 }]

[contacts]
joint = "stone-joint"
tolerance = 1e-6

[analysis]
type = "static"
"#;

const SLOPE: &str = r#"title = "Toppling rock slope (Goodman and Bray 1976 worked example)"
# Columns 10 m wide, joints dipping 60 degrees into the slope, base stepped at 35.8
# degrees, heights 4, 8, ..., 40 (crest), 34.1, ..., 4.6 m; gamma = 25 kN/m3.
# Limit equilibrium: the slope just stands at phi = 38.15 degrees; here phi = 40.

[model]
plane = "strain"
thickness = 1.0
gravity = [0.0, -9.81]

[[material]]
name = "rock"
lame_lambda = 10e9
lame_mu = 10e9
unit_weight = 25e3

[[joint]]
name = "rock-joint"
normal_modulus = 10e9
shear_modulus = 1e9
band = 0.05
friction_angle = 40.0

[[generate]]
type = "slope"
material = "rock"
column_width = 10.0
joint_dip = 60.0
step = 1.0
heights = [4.0, 8.0, 12.0, 16.0, 20.0, 24.0, 28.0, 32.0, 36.0, 40.0, 34.1, 28.2, 22.3, 16.4, 10.5, 4.6]

[contacts]
joint = "rock-joint"
tolerance = 1e-6

[analysis]
type = "static"
"#;

const TUNNEL: &str = r#"title = "Circular tunnel in jointed rock"
# A 20 m x 20 m domain, a tunnel of radius 3 m at its centre, two joint sets (dips 30 and
# 120 degrees, spacing 2 m), inside a fixed frame 1 m thick.

[model]
plane = "strain"
thickness = 1.0
gravity = [0.0, -9.81]

[[material]]
name = "rock"
lame_lambda = 10e9
lame_mu = 10e9
unit_weight = 26e3

[[joint]]
name = "rock-joint"
normal_modulus = 20e9
shear_modulus = 2e9
band = 0.010
friction_angle = 35.0
cohesion = 50e3

[[generate]]
type = "tunnel"
material = "rock"
width = 20.0
height = 20.0
frame = 1.0
joint_sets = [
  { dip = 30.0, spacing = 2.0 },
  { dip = 120.0, spacing = 2.0 },
]
opening = { shape = "circle", radius = 3.0, segments = 32 }

[contacts]
joint = "rock-joint"
tolerance = 1e-6

[analysis]
type = "static"
"#;

/// The Eindhoven shear walls (Raijmakers and Vermeltfoort 1992) as Lourenço and Rots
/// (1997) modelled them: one text, the wall's name, its pre-compression (N/mm²) and the
/// force on the beam (N) filled in.
macro_rules! eindhoven_wall {
    ($wall:literal, $p:literal, $force:literal) => {
        concat!(
            "title = \"Eindhoven shear wall ",
            $wall,
            ", pre-compression ",
            $p,
            " N/mm2 (Raijmakers and Vermeltfoort 1992)\"\n",
            r#"# The micro-model of Lourenco and Rots (1997), docs/validation.md V8 (docs/performance.md,
# "Eindhoven walls"): solid clay bricks 210 x 52 x 100 mm with 10 mm mortar joints,
# modelled as expanded bricks (brick plus half a joint all round) with zero-thickness
# joints; E = 16700 N/mm2, nu = 0.15 (plane stress, 100 mm thick). Every full brick is
# split at mid-length by a potential crack (split_bricks) with the brick's tensile
# strength 2.0 N/mm2. The 16 free courses (990 x 992 mm) stand between the bottom and
# top courses clamped in steel beams: a fixed base and a rigid steel beam, the bed joints
# to them mortar. The pre-compression is a load on the beam (p x 990 x 100 mm); the beam
# is then pushed 4 mm with its rotation and its vertical motion held ("in a confined
# way": Lourenco 1996), the load followed by the dissipation-based arc length through
# the peak and the snap-backs (curve.csv: force_x_N against ux_m). Mortar: kn = 82 N/mm3, ks = 36 N/mm3 (over a 10 mm band), ft = 0.25 N/mm2,
# G_f^I = 0.018 N/mm, c = 0.35 N/mm2, tan(phi) = 0.75, G_f^II = 0.125 N/mm, compressive
# strength 10.5 N/mm2 (docs/validation.md V8); cap C_ss = 9, G_fc = 5 N/mm, kappa_p =
# 0.093 mm, brick cracks G_f^I = 0.08 N/mm (Lourenco 1996 as recalled, not checked
# against the source); brick cracks c = 1.4 ft, phi = 45 deg, G_f^II = 10 G_f^I
# (assumed). The bricks are meshed at 26 mm (two triangles' height through a brick's
# 52 mm): the first peak changes by less than 3 % when they are meshed at 13 mm
# (docs/performance.md, "Eindhoven walls").

[model]
plane = "stress"
thickness = 0.1
gravity = [0.0, -9.81]

[[material]]
name = "brick"
lame_lambda = 3.1118e9
lame_mu = 7.2609e9
unit_weight = 18e3

[[material]]
name = "steel"
lame_lambda = 121e9
lame_mu = 81e9
unit_weight = 0.0

[[joint]]
name = "mortar"
normal_modulus = 8.2e8
shear_modulus = 3.6e8
band = 0.010
friction_angle = 36.8699
cohesion = 0.35e6
tensile_strength = 0.25e6
softening = "exponential"
fracture_energy_i = 18.0
fracture_energy_ii = 125.0
compressive_strength = 10.5e6
cap_shear_factor = 9.0
compressive_fracture_energy = 5000.0
cap_peak_displacement = 0.093e-3

# the potential cracks at mid-length of the bricks (a stiff dummy band)
[[joint]]
name = "brick"
normal_modulus = 1e13
shear_modulus = 1e13
band = 0.010
friction_angle = 45.0
cohesion = 2.8e6
tensile_strength = 2.0e6
softening = "exponential"
fracture_energy_i = 80.0
fracture_energy_ii = 800.0
within = "unit"

[[generate]]
type = "wall"
material = "brick"
courses = 16
bricks_per_course = 4.5
brick_length = 0.21
brick_height = 0.052
joint = 0.01
base = true
top_beam = false
split_bricks = true
mesh_size = 0.026

[[block]]
name = "beam"
material = "steel"
kind = "rigid"
vertices = [[0.0, 0.992], [0.99, 0.992], [0.99, 1.092], [0.0, 1.092]]

[[load]]
block = "beam"
"#,
            "force = [0.0, ",
            $force,
            "]\n",
            r#"
[contacts]
joint = "mortar"
tolerance = 1e-6

[analysis]
type = "static"
load_steps = 80
push_block = "beam"
push_displacement = [0.004, 0.0]
path = "dissipation"
tolerance = 1e-5
# an increment that fails every constraint at its least step, its best iterate within
# 10 x the tolerance, is taken there (J7D's iterations stall at 1.0-3.3e-5 of the load
# at 11 states past its peak: docs/performance.md, "Eindhoven walls")
accept_residual = 1e-4
"#
        )
    };
}

const EINDHOVEN: &str = eindhoven_wall!("J4D/J5D", "0.30", "-29.7e3");
const EINDHOVEN_J6D: &str = eindhoven_wall!("J6D", "1.21", "-119.79e3");
const EINDHOVEN_J7D: &str = eindhoven_wall!("J7D", "2.12", "-209.88e3");

#[cfg(test)]
mod tests {
    use super::super::generate::{generate, TYPES};
    use super::EXAMPLES;

    #[test]
    fn every_example_parses_and_generates() {
        let mut names: Vec<&str> = EXAMPLES.iter().map(|e| e.0).collect();
        for t in TYPES {
            assert!(names.contains(t), "no example for {t}");
        }
        assert!(names.contains(&"wall-window"));
        names.sort();
        names.dedup();
        assert_eq!(names.len(), EXAMPLES.len(), "example names repeat");
        for (name, desc, text) in EXAMPLES {
            assert!(!desc.is_empty());
            let doc: toml::Table = text.parse().unwrap_or_else(|e| panic!("{name}: {e}"));
            let Some(gens) = doc.get("generate").and_then(|g| g.as_array()) else {
                // blocks given one by one (the column's drums): they parse and mesh in
                // tests/examples.rs
                assert!(
                    doc["block"].as_array().is_some_and(|b| b.len() >= 2),
                    "{name}"
                );
                continue;
            };
            assert_eq!(gens.len(), 1, "{name}");
            let mut params = gens[0].as_table().unwrap().clone();
            let kind = params.remove("type").unwrap().as_str().unwrap().to_string();
            let mat = params
                .remove("material")
                .unwrap()
                .as_str()
                .unwrap()
                .to_string();
            for k in ["name", "base_material", "kind", "mesh_size"] {
                params.remove(k);
            }
            let mats = doc["material"].as_array().unwrap();
            assert!(
                mats.iter().any(|m| m["name"].as_str() == Some(&mat)),
                "{name}: material {mat}"
            );
            let joint = doc["contacts"]["joint"].as_str().unwrap();
            assert!(doc["joint"]
                .as_array()
                .unwrap()
                .iter()
                .any(|j| j["name"].as_str() == Some(joint)));
            assert!(matches!(
                doc["analysis"]["type"].as_str(),
                Some("static") | Some("dynamic")
            ));
            let blocks = generate(&kind, &params).unwrap_or_else(|e| panic!("{name}: {e:?}"));
            assert!(
                blocks.len() >= 2 && blocks.len() < 300,
                "{name}: {} blocks",
                blocks.len()
            );
            assert!(blocks.iter().any(|b| b.fixed) && blocks.iter().any(|b| !b.fixed));
        }
    }
}
