//! Failure mechanism (docs/theory.md §4): which blocks move in the failing increment and how.
//! The moving blocks are found from the failing increment (the mode); how each moves
//! comes from the states of its contacts in the failing trial: a block with open
//! contacts rotates about the closed ones (toppling or hinging), and does so while sliding
//! when its closed contacts slip; a block whose contacts slip with none open slides. When
//! the states say nothing (all stick), the kinematics decide: translation with little
//! rotation is sliding, rotation toppling.

use crate::material::{ContactState, MohrCoulomb};

/// The strength data the pivot check needs.
struct PivotStrength {
    tan_phi: f64,
    cohesion: f64,
    thickness: f64,
}
use crate::mesh::{BlockDofs, Mesh};
use crate::scene::Scene;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Motion {
    None,
    Sliding,
    Toppling,
    SlidingToppling,
    /// No chain of contacts holds the block (an extension of the values of docs/outputs.md, "summary.json").
    Falling,
}

impl Motion {
    pub fn as_str(self) -> &'static str {
        match self {
            Motion::None => "none",
            Motion::Sliding => "sliding",
            Motion::Toppling => "toppling",
            Motion::SlidingToppling => "sliding+toppling",
            Motion::Falling => "falling",
        }
    }
}

/// The mechanism: each free block's motion and the overall mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Mechanism {
    /// (block index, motion) for every free block.
    pub blocks: Vec<(usize, Motion)>,
    /// "sliding" | "toppling" | "sliding+toppling" | "mixed" (docs/outputs.md, "summary.json").
    pub mode: String,
}

impl Mechanism {
    pub fn moving(&self) -> Vec<usize> {
        self.blocks
            .iter()
            .filter(|b| b.1 != Motion::None)
            .map(|b| b.0)
            .collect()
    }
}

/// Rigid fit (translation of the centroid, rotation) of the mode `dq` on a block.
fn block_mode(mesh: &Mesh, b: usize, dq: &[f64]) -> ([f64; 2], f64) {
    let blk = &mesh.blocks[b];
    if let BlockDofs::Rigid { first, .. } = blk.dofs {
        let f = first as usize;
        return ([dq[f], dq[f + 1]], dq[f + 2]);
    }
    let nodes: Vec<u32> = blk.nodes.clone().collect();
    let c = blk.centroid;
    let v: Vec<[f64; 2]> = nodes
        .iter()
        .map(|&n| mesh.node_displacement(n, dq))
        .collect();
    let k = nodes.len() as f64;
    let t = v
        .iter()
        .fold([0.0, 0.0], |a, d| [a[0] + d[0] / k, a[1] + d[1] / k]);
    let pc = nodes.iter().fold([0.0, 0.0], |a, &n| {
        [
            a[0] + mesh.nodes[n as usize][0] / k,
            a[1] + mesh.nodes[n as usize][1] / k,
        ]
    });
    let (mut num, mut den) = (0.0, 0.0);
    for (i, &n) in nodes.iter().enumerate() {
        let r = [
            mesh.nodes[n as usize][0] - pc[0],
            mesh.nodes[n as usize][1] - pc[1],
        ];
        let d = [v[i][0] - t[0], v[i][1] - t[1]];
        num += r[0] * d[1] - r[1] * d[0];
        den += r[0] * r[0] + r[1] * r[1];
    }
    let w = if den > 0.0 { num / den } else { 0.0 };
    // translation of the polygon centroid
    let tc = [t[0] - w * (c[1] - pc[1]), t[1] + w * (c[0] - pc[0])];
    (tc, w)
}

/// Classify the mode `dq` (an increment of unknowns at failure) in the configuration `mesh`.
/// Whether a rotating block also slides at its pivot: the contacts it rests on (closed
/// contacts with blocks that do not move) must carry the block's load (its external force
/// plus the forces of the moving blocks leaning on it); Coulomb at the pivot decides, as
/// in Hoek and Bray's chart (the pivot of a block on an incline slides when α > φ).
/// `contacts_of_b`: the contacts of block `b`, in ascending order.
#[allow(clippy::too_many_arguments)]
fn pivot_slips(
    mesh: &Mesh,
    b: usize,
    contacts_of_b: &[u32],
    moving: &[bool],
    loads: &[[f64; 2]],
    forces: &[[f64; 2]],
    states: &[ContactState],
    law: &PivotStrength,
) -> Option<bool> {
    let mut r = loads[b];
    let (mut n_sum, mut area) = ([0.0, 0.0], 0.0);
    for &k in contacts_of_b {
        let k = k as usize;
        let c = &mesh.contacts[k];
        let (other, sign) = if c.block_l as usize == b {
            (c.block_m as usize, 1.0)
        } else if c.block_m as usize == b {
            (c.block_l as usize, -1.0)
        } else {
            continue;
        };
        if states[k] == ContactState::Open {
            continue;
        }
        if moving[other] {
            // force on b from this contact: +(Fₙ n + Fₛ s) on side l, the opposite on m
            let f = forces[k];
            let s = [-c.normal[1], c.normal[0]];
            r[0] += sign * (f[0] * c.normal[0] + f[1] * s[0]);
            r[1] += sign * (f[0] * c.normal[1] + f[1] * s[1]);
        } else {
            // normal pointing from the support into b
            n_sum[0] -= sign * c.normal[0];
            n_sum[1] -= sign * c.normal[1];
            area += c.length;
        }
    }
    let nn = n_sum[0].hypot(n_sum[1]);
    if nn == 0.0 {
        return None;
    }
    let n = [n_sum[0] / nn, n_sum[1] / nn];
    // the support reaction balances r: reaction = −r
    let rn = -(r[0] * n[0] + r[1] * n[1]); // > 0: the support pushes on b
    let rt = (-r[0] * n[1] + r[1] * n[0]).abs();
    let cohesion = law.cohesion * area * law.thickness;
    Some(rn <= 0.0 || rt > law.tan_phi * rn + cohesion)
}

/// Classify the mode `dq` (an increment of unknowns at failure) in the configuration
/// `mesh`, with the contact states and forces of the failing trial and the external force
/// resultant (N) on every block.
pub fn classify(
    scene: &Scene,
    mesh: &Mesh,
    dq: &[f64],
    states: &[ContactState],
    forces: &[[f64; 2]],
    loads: &[[f64; 2]],
) -> Mechanism {
    let law = MohrCoulomb::from_joint(
        &scene.joints[scene
            .contacts
            .joint
            .min(scene.joints.len().saturating_sub(1))],
    );
    let law = &PivotStrength {
        tan_phi: law.tan_phi,
        cohesion: law.cohesion,
        thickness: scene.model.thickness,
    };
    let nb = mesh.blocks.len();
    let modes: Vec<Option<([f64; 2], f64, f64)>> = (0..nb)
        .map(|b| {
            if mesh.blocks[b].dofs == BlockDofs::Fixed {
                return None;
            }
            let (t, w) = block_mode(mesh, b, dq);
            let l = mesh.blocks[b].area.abs().sqrt();
            Some((t, w, l))
        })
        .collect();
    let mag = |m: &([f64; 2], f64, f64)| m.0[0].hypot(m.0[1]) + m.1.abs() * m.2;
    let max = modes.iter().flatten().map(mag).fold(0.0, f64::max);
    let moving: Vec<bool> = modes
        .iter()
        .map(|m| m.as_ref().is_some_and(|m| max > 0.0 && mag(m) > 0.1 * max))
        .collect();
    // each block's contacts, in ascending order (one pass: scanning every contact for
    // every block took hours on a 10⁶-unknown wall, 3·10⁵ blocks × 2·10⁶ contacts)
    let mut contacts_of: Vec<Vec<u32>> = vec![Vec::new(); nb];
    for (k, c) in mesh.contacts.iter().enumerate() {
        contacts_of[c.block_l as usize].push(k as u32);
        if c.block_m != c.block_l {
            contacts_of[c.block_m as usize].push(k as u32);
        }
    }
    let mut blocks = Vec::new();
    let mut carried = Vec::new();
    for (b, m) in modes.iter().enumerate() {
        let Some(m) = m else { continue };
        let size = mag(m);
        if max == 0.0 || size <= 0.1 * max || !size.is_finite() {
            blocks.push((b, Motion::None));
            continue;
        }
        let (mut open, mut closed, mut slipping) = (0, 0, 0);
        for &k in &contacts_of[b] {
            let k = k as usize;
            let c = &mesh.contacts[k];
            match states.get(k).copied().unwrap_or(ContactState::Stick) {
                ContactState::Open => open += 1,
                ContactState::Slip => {
                    closed += 1;
                    // a slip state counts only where the mode really slides
                    let v = mesh.node_displacement(c.node_m, dq);
                    let w = c.at_l(|n| mesh.node_displacement(n, dq));
                    let rel = [v[0] - w[0], v[1] - w[1]];
                    let tang = (-rel[0] * c.normal[1] + rel[1] * c.normal[0]).abs();
                    if tang > 0.05 * size {
                        slipping += 1
                    }
                }
                ContactState::Stick => closed += 1,
            }
        }
        let rotates = m.1.abs() * m.2 >= 0.2 * m.0[0].hypot(m.0[1]);
        let motion = match (open > 0, slipping > 0) {
            (true, true) if closed == slipping => Motion::SlidingToppling,
            (true, _) => match pivot_slips(
                mesh,
                b,
                &contacts_of[b],
                &moving,
                loads,
                forces,
                states,
                law,
            ) {
                Some(true) => Motion::SlidingToppling,
                _ => Motion::Toppling,
            },
            (false, true) => Motion::Sliding,
            // carried by its neighbours (every contact sticks): decided below
            (false, false) => Motion::None,
        };
        blocks.push((b, motion));
        carried.push((b, rotates));
    }
    // A moving block whose contacts all stick moves with a rigid part of the mechanism:
    // it takes the mechanism's kind from the blocks whose contacts open or slip, or, when
    // there are none, from its own kinematics.
    let defining: std::collections::BTreeSet<Motion> = blocks
        .iter()
        .map(|b| b.1)
        .filter(|m| *m != Motion::None)
        .collect();
    for &(b, rotates) in &carried {
        let entry = blocks.iter_mut().find(|e| e.0 == b).unwrap();
        if entry.1 != Motion::None || !moving[b] {
            continue;
        }
        entry.1 = if defining.len() == 1 {
            *defining.iter().next().unwrap()
        } else if defining.contains(&Motion::Toppling) || rotates {
            Motion::Toppling
        } else {
            Motion::Sliding
        };
    }
    let kinds: std::collections::BTreeSet<&str> = blocks
        .iter()
        .filter(|b| b.1 != Motion::None)
        .map(|b| b.1.as_str())
        .collect();
    let mode = if kinds.len() == 1 {
        kinds.into_iter().next().unwrap().to_string()
    } else {
        "mixed".to_string()
    };
    Mechanism { blocks, mode }
}
