//! Scene: the validated model read from a TOML file (docs/scene-reference.md).
//!
//! [`parse`] turns text into a [`Scene`], checking everything before any work is done;
//! [`generate`] expands `[[generate]]` entries into blocks; [`import`] reads blocks from
//! Gmsh and DXF files (`[[import]]`); [`examples`] holds the
//! built-in example scenes of `dfem example`.

pub mod examples;
pub mod generate;
pub mod ground_motion;
pub mod import;
pub mod parse;
pub mod settings;

pub use parse::{load, parse_str};
pub use settings::{AnalysisSettings, DynamicSettings, StaticSettings};

/// 2D idealisation of the out-of-plane direction (docs/theory.md §1).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    Strain,
    Stress,
}

/// `[model]`: plane, thickness (m), gravity (m/s²).
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    pub plane: Plane,
    /// Out-of-plane thickness `t`, m.
    pub thickness: f64,
    /// Gravity acceleration vector, m/s².
    pub gravity: [f64; 2],
}

/// `[in_situ]`: the stress of the rock before the excavation (docs/theory.md, "In-situ
/// stress"), a field linear in the height: σ(y) = `stress` + (y − `datum`) `gradient`
/// (σxx, σyy, σxy; Pa, tension positive). Static and capacity analyses start from it:
/// the blocks' triangles carry it and every contact the traction it puts on the joint,
/// and the gravity phase releases the out-of-balance force of that state (the
/// excavation) in its increments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InSitu {
    /// σ at y = `datum` (Pa).
    pub stress: [f64; 3],
    /// dσ/dy (Pa/m).
    pub gradient: [f64; 3],
    /// m.
    pub datum: f64,
}

impl InSitu {
    /// The in-situ stress (σxx, σyy, σxy) (Pa) at height `y` (m).
    pub fn at(&self, y: f64) -> [f64; 3] {
        let h = y - self.datum;
        [0, 1, 2].map(|i| self.stress[i] + h * self.gradient[i])
    }
}

/// `[[material]]`: an elastic (Kelvin–Voigt) block material (docs/theory.md §2).
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub name: String,
    /// Lamé λ, Pa.
    pub lame_lambda: f64,
    /// Lamé μ (shear modulus), Pa.
    pub lame_mu: f64,
    /// Unit weight γ, N/m³; mass density ρ = γ / 9.81.
    pub unit_weight: f64,
    /// Viscous Lamé λ*, Pa·s.
    pub viscous_lambda: f64,
    /// Viscous Lamé μ*, Pa·s.
    pub viscous_mu: f64,
}

/// Standard gravity used to turn a unit weight into a mass density (docs/theory.md, "Units").
pub const STANDARD_GRAVITY: f64 = 9.81;

impl Material {
    /// Mass density ρ = γ / g, kg/m³.
    pub fn density(&self) -> f64 {
        self.unit_weight / STANDARD_GRAVITY
    }
}

/// `[[joint]]`: band-type contact properties (docs/theory.md §3).
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub name: String,
    /// Eₙ, Pa.
    pub normal_modulus: f64,
    /// Gₛ, Pa.
    pub shear_modulus: f64,
    /// Eₙ*, Pa·s.
    pub normal_viscosity: f64,
    /// Gₛ*, Pa·s.
    pub shear_viscosity: f64,
    /// Band thickness h, m.
    pub band: f64,
    /// Friction angle φ, degrees.
    pub friction_angle: f64,
    /// Cohesion c, Pa.
    pub cohesion: f64,
    /// Tensile strength fₜ, Pa.
    pub tensile_strength: f64,
    /// Softening of fₜ and c (`softening`; docs/theory.md, "Softening joints").
    pub softening: JointSoftening,
    /// Mode-I fracture energy G_f^I, N/m (softening joints).
    pub fracture_energy_i: f64,
    /// Mode-II fracture energy G_f^II, N/m (softening joints).
    pub fracture_energy_ii: f64,
    /// The compression cap of a softening joint (`compressive_strength`), if any.
    pub cap: Option<JointCap>,
    /// Dilatancy angle ψ₀ of a softening joint, degrees (`dilatancy_angle`; 0: none).
    pub dilatancy_angle: f64,
    /// σᵤ, Pa (`dilatancy_stress`): the compression at which the dilatancy vanishes.
    pub dilatancy_stress: f64,
    /// Contacts between two blocks of one masonry unit (the halves of a split brick)
    /// take this joint (`within = "unit"`).
    pub within_unit: bool,
    /// Indices into [`Scene::blocks`]: contacts touching any of them take this joint
    /// instead of the `[contacts]` one (`blocks`; empty: none).
    pub blocks: Vec<usize>,
}

/// `[[joint]] compressive_strength` and its companions: the elliptic compression cap of
/// a softening joint (docs/theory.md, "Compression cap"; Lourenço and Rots 1997).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointCap {
    /// fₘ, Pa.
    pub compressive_strength: f64,
    /// C_ss, the weight of the shear stress in the cap (`cap_shear_factor`, default 9).
    pub shear_factor: f64,
    /// G_fc, N/m (`compressive_fracture_energy`); `None`: perfectly plastic cap.
    pub fracture_energy: Option<f64>,
    /// κₚ, m, the plastic relative displacement at the peak (`cap_peak_displacement`;
    /// with `compressive_fracture_energy`).
    pub peak_displacement: f64,
}

/// `[[joint]] softening`: how the tensile strength and the cohesion degrade.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum JointSoftening {
    /// Constant strengths (the Mohr–Coulomb band of docs/theory.md §3).
    #[default]
    None,
    /// Exponential softening governed by the fracture energies (Lourenço and Rots 1997).
    Exponential,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Support {
    Free,
    Fixed,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlockKind {
    Deformable,
    Rigid,
}

/// A block: a simple counter-clockwise polygon of one material.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    pub name: String,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// Counter-clockwise vertices, m.
    pub vertices: Vec<[f64; 2]>,
    pub support: Support,
    pub kind: BlockKind,
    /// Target triangle edge length for interior refinement, m (`None`: corners and contact nodes only).
    pub mesh_size: Option<f64>,
    /// Prescribed translation of a fixed block (m), applied after gravity (a settlement or
    /// a fault offset).
    pub prescribed: Option<[f64; 2]>,
    /// Line of the block's table (or of its `[[generate]]` entry) in the scene file.
    pub line: Option<usize>,
    /// The masonry unit (brick) the block is part of: the two halves of a brick split by
    /// a potential crack (`split_bricks` of the wall generator) share one; `None`: none.
    pub unit: Option<usize>,
}

/// `[contacts]`: how contacts are found between touching blocks.
#[derive(Debug, Clone, PartialEq)]
pub struct Contacts {
    /// Index into [`Scene::joints`] of the joint used by every contact.
    pub joint: usize,
    /// Edges closer than this touch, m.
    pub tolerance: f64,
}

/// `[[load]]`: a force on a block, N (resultant).
#[derive(Debug, Clone, PartialEq)]
pub struct Load {
    /// Index into [`Scene::blocks`].
    pub block: usize,
    /// Resultant force, N.
    pub force: [f64; 2],
    /// `None`: spread over the block like a body force; `Some(segment)`: spread uniformly
    /// along the part of the block's boundary lying on that segment.
    pub along: Option<[[f64; 2]; 2]>,
    pub line: Option<usize>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AnalysisType {
    Static,
    Capacity,
    Dynamic,
}

/// `[analysis]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Analysis {
    pub kind: AnalysisType,
    /// Static: horizontal body force as a fraction of the weight, applied after gravity.
    pub lateral: f64,
    /// Number of load increments.
    pub load_steps: usize,
    /// Capacity: +1 or −1 (direction of the lateral body force).
    pub direction: f64,
    /// Dynamic: time step and duration, s.
    pub dt: Option<f64>,
    pub duration: Option<f64>,
    /// Dynamic: the ground acceleration (`ground_motion`), one component per direction
    /// shaken (empty: none).
    pub ground_motion: Vec<ground_motion::GroundMotion>,
    /// Dynamic: the frame the ground motion enters (`frame`).
    pub frame: ground_motion::Frame,
    /// The settings of the analysis type: the static driver's (static and capacity) or
    /// the time integration's (dynamic), validated when the scene is read.
    pub settings: AnalysisSettings,
}

/// `[output]`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Output {
    /// Blocks written to history.csv (empty: every free block).
    pub track: Vec<String>,
    /// Write ParaView files (default true).
    pub vtk: bool,
    /// Dynamic: when the ParaView frames are written (`every`, `frame_interval`, or
    /// `dfem run --frames N`).
    pub frames: Frames,
    /// Dynamic: a checkpoint (`checkpoint.bin`, for `dfem run --resume`) every this many
    /// time steps; `None` (default): every [`crate::output::CHECKPOINT_SECONDS`] s of
    /// wall time.
    pub checkpoint_every: Option<usize>,
}

/// When a dynamic run writes its ParaView frames: always at t = 0 and at the last step
/// reached, and in between by this rule (docs/scene-reference.md, "`[output]`").
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Frames {
    /// Neither `every` nor `frame_interval`: one frame per
    /// [`crate::analysis::dynamics::FRAME_INTERVAL`] s of simulated time, the interval
    /// widened so that at most [`crate::analysis::dynamics::MAX_FRAMES`] follow t = 0.
    #[default]
    Default,
    /// `every = k`: at every k-th time step.
    Steps(usize),
    /// `frame_interval = s`: one frame per s seconds of simulated time.
    Interval(f64),
    /// `dfem run --frames N`: N frames after t = 0, evenly in simulated time.
    Count(usize),
}

/// A validated scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    pub title: String,
    pub model: Model,
    pub materials: Vec<Material>,
    pub joints: Vec<Joint>,
    pub blocks: Vec<Block>,
    pub contacts: Contacts,
    pub loads: Vec<Load>,
    pub analysis: Analysis,
    pub output: Output,
    /// `[in_situ]`, if given.
    pub in_situ: Option<InSitu>,
    /// Where the scene came from (for error messages); `None` for built-in text.
    pub file: Option<std::path::PathBuf>,
    /// Warnings found while reading (clockwise polygons reversed, ...), one line each.
    pub warnings: Vec<String>,
}

impl Scene {
    pub fn block_index(&self, name: &str) -> Option<usize> {
        self.blocks.iter().position(|b| b.name == name)
    }

    /// The joint (index into [`Scene::joints`]) of a contact between blocks `a` and `b`:
    /// within one masonry unit the first joint with `within = "unit"`; else the first
    /// joint whose `blocks` names either of them; else the `[contacts]` joint.
    pub fn joint_of(&self, a: usize, b: usize) -> usize {
        let unit = |i: usize| self.blocks.get(i).and_then(|x| x.unit);
        if unit(a).is_some() && unit(a) == unit(b) {
            if let Some(j) = self.joints.iter().position(|j| j.within_unit) {
                return j;
            }
        }
        self.joints
            .iter()
            .position(|j| j.blocks.contains(&a) || j.blocks.contains(&b))
            .unwrap_or(self.contacts.joint)
    }
}
