//! The outline of a meshed surface: the one closed loop of the edges that belong to a
//! single element (triangle or quadrangle), counter-clockwise.
//!
//! Each element is first oriented counter-clockwise (by its signed area), so every
//! interior edge is crossed once in each direction and cancels; the edges left form the
//! boundary. A block is a simple polygon, so a surface whose boundary is not one loop (a
//! hole, two pieces, two loops touching at a node) is refused with the reason.

use crate::geometry::polygon::signed_area;
use std::collections::{BTreeMap, HashMap};

/// Why a set of elements has no single outline.
#[derive(Debug, Clone, PartialEq)]
pub enum OutlineDefect {
    /// No elements.
    Empty,
    /// An element refers to a node that has no coordinates.
    MissingNode(u64),
    /// An element has zero area (collinear or repeated nodes).
    Degenerate,
    /// An edge is shared by more than two elements.
    NonManifold(u64, u64),
    /// Two boundary loops meet at this node.
    Pinched(u64),
    /// The boundary is several loops (a hole or separate pieces): the number of loops.
    SeveralLoops(usize),
}

impl OutlineDefect {
    /// What is wrong and how to fix it, for the user.
    pub fn explain(&self) -> (String, String) {
        match self {
            OutlineDefect::Empty => (
                "the surface has no triangles or quadrangles".into(),
                "mesh the surface in 2D (Gmsh: Mesh > 2D) before saving".into(),
            ),
            OutlineDefect::MissingNode(n) => (
                format!("an element uses node {n}, which is not in $Nodes"),
                "save the mesh again from Gmsh (the file is incomplete)".into(),
            ),
            OutlineDefect::Degenerate => (
                "an element has zero area".into(),
                "remesh the surface (its elements must not be flat)".into(),
            ),
            OutlineDefect::NonManifold(a, b) => (
                format!("the edge between nodes {a} and {b} is shared by more than two elements"),
                "make each block one plane surface whose elements do not overlap".into(),
            ),
            OutlineDefect::Pinched(n) => (
                format!("the outline touches itself at node {n}"),
                "split the surface into blocks that are simple polygons".into(),
            ),
            OutlineDefect::SeveralLoops(k) => (
                format!("the surface's boundary is {k} separate loops (a hole, or several pieces)"),
                "make each block one surface without holes: split a surface with a hole in two, give separate pieces separate surfaces".into(),
            ),
        }
    }
}

/// The counter-clockwise outline of `elements` (each a list of node ids, corners only)
/// with node coordinates `xy` (m).
pub fn outline(
    elements: &[Vec<u64>],
    xy: &HashMap<u64, [f64; 2]>,
) -> Result<Vec<[f64; 2]>, OutlineDefect> {
    if elements.is_empty() {
        return Err(OutlineDefect::Empty);
    }
    // undirected edge -> (count, the directed edge of its first element)
    let mut edges: BTreeMap<(u64, u64), (usize, (u64, u64))> = BTreeMap::new();
    for e in elements {
        let mut pts = Vec::with_capacity(e.len());
        for n in e {
            pts.push(*xy.get(n).ok_or(OutlineDefect::MissingNode(*n))?);
        }
        let area = signed_area(&pts);
        if area == 0.0 || !area.is_finite() {
            return Err(OutlineDefect::Degenerate);
        }
        let k = e.len();
        for i in 0..k {
            let (mut a, mut b) = (e[i], e[(i + 1) % k]);
            if area < 0.0 {
                std::mem::swap(&mut a, &mut b);
            }
            let entry = edges.entry((a.min(b), a.max(b))).or_insert((0, (a, b)));
            entry.0 += 1;
            if entry.0 > 2 {
                return Err(OutlineDefect::NonManifold(a.min(b), a.max(b)));
            }
        }
    }
    let mut next: BTreeMap<u64, u64> = BTreeMap::new();
    for (count, (a, b)) in edges.values() {
        if *count == 1 && next.insert(*a, *b).is_some() {
            return Err(OutlineDefect::Pinched(*a));
        }
    }
    // walk the loop from the smallest node id (deterministic)
    let (&start, _) = next.iter().next().ok_or(OutlineDefect::Empty)?;
    let mut ring = vec![start];
    let mut at = next[&start];
    while at != start {
        ring.push(at);
        at = match next.get(&at) {
            Some(&n) if ring.len() <= next.len() => n,
            _ => return Err(OutlineDefect::SeveralLoops(count_loops(&next))),
        };
    }
    if ring.len() < next.len() {
        let loops = count_loops(&next);
        return Err(OutlineDefect::SeveralLoops(loops));
    }
    Ok(ring.iter().map(|n| xy[n]).collect())
}

/// The number of closed loops of the successor map.
fn count_loops(next: &BTreeMap<u64, u64>) -> usize {
    let mut seen = std::collections::BTreeSet::new();
    let mut loops = 0;
    for &s in next.keys() {
        if seen.contains(&s) {
            continue;
        }
        loops += 1;
        let mut at = s;
        while seen.insert(at) {
            match next.get(&at) {
                Some(&n) => at = n,
                None => break,
            }
        }
    }
    loops
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> HashMap<u64, [f64; 2]> {
        // 3 x 3 nodes on the unit square's quarter points... 0..=2 in x and y
        let mut m = HashMap::new();
        for j in 0..4u64 {
            for i in 0..4u64 {
                m.insert(1 + i + 4 * j, [i as f64, j as f64]);
            }
        }
        m
    }

    fn quad(i: u64, j: u64) -> Vec<u64> {
        let n = |i: u64, j: u64| 1 + i + 4 * j;
        vec![n(i, j), n(i + 1, j), n(i + 1, j + 1), n(i, j + 1)]
    }

    #[test]
    fn outline_of_a_mixed_mesh_is_its_boundary_counter_clockwise() {
        let xy = grid();
        // a 2 x 1 rectangle: one quad (clockwise on purpose) and two triangles
        let mut q = quad(0, 0);
        q.reverse();
        let els = vec![q, vec![2, 3, 7], vec![2, 7, 6]];
        let o = outline(&els, &xy).unwrap();
        assert_eq!(o.len(), 6, "{o:?}");
        // area 2, counter-clockwise: the shoelace sum is exact for these integers
        assert_eq!(signed_area(&o), 2.0);
    }

    #[test]
    fn a_hole_and_two_pieces_are_refused() {
        let xy = grid();
        // 3 x 3 squares without the middle one: a ring
        let mut ring = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                if (i, j) != (1, 1) {
                    ring.push(quad(i, j));
                }
            }
        }
        assert_eq!(outline(&ring, &xy), Err(OutlineDefect::SeveralLoops(2)));
        let apart = vec![quad(0, 0), quad(2, 0)];
        assert_eq!(outline(&apart, &xy), Err(OutlineDefect::SeveralLoops(2)));
        let corner = vec![quad(0, 0), quad(1, 1)];
        assert!(matches!(
            outline(&corner, &xy),
            Err(OutlineDefect::Pinched(_))
        ));
        assert_eq!(outline(&[], &xy), Err(OutlineDefect::Empty));
        assert_eq!(
            outline(&[vec![1, 2, 99]], &xy),
            Err(OutlineDefect::MissingNode(99))
        );
        assert_eq!(
            outline(&[vec![1, 2, 3]], &xy),
            Err(OutlineDefect::Degenerate)
        );
    }
}
