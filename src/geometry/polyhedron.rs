//! Convex polyhedral blocks, the blocks of three-dimensional scenes (docs/theory.md,
//! "Three-dimensional blocks"): the checks a block must pass before it is analysed, its
//! faces as planes, and its mass properties.
//!
//! A block is given by its vertices (m) and its faces, each a list of vertex indices
//! counter-clockwise seen from outside the block, so that the right-hand rule gives the
//! outward normal. The checks ([`Polyhedron::check`]) return the first defect found as a
//! [`PolyhedronDefect`], which says what is wrong and how to mend it; the scene reader
//! adds the file and the line.

/// A point or a vector in space (m).
pub type Vec3 = [f64; 3];

pub fn sub3(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

pub fn add3(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub fn scale3(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub fn dot3(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross3(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn norm3(a: Vec3) -> f64 {
    dot3(a, a).sqrt()
}

/// A convex polyhedron: vertices (m) and faces (vertex indices, counter-clockwise seen
/// from outside).
#[derive(Debug, Clone, PartialEq)]
pub struct Polyhedron {
    pub vertices: Vec<Vec3>,
    pub faces: Vec<Vec<usize>>,
}

/// What makes a polyhedron unfit to be a block, with the indices (0-based) that locate it.
#[derive(Debug, Clone, PartialEq)]
pub enum PolyhedronDefect {
    /// Fewer than 4 vertices or 4 faces: no volume can be enclosed.
    TooFew { vertices: usize, faces: usize },
    /// A coordinate that is not a finite number.
    NotFinite { vertex: usize },
    /// A face names a vertex that does not exist.
    BadIndex { face: usize, index: usize },
    /// A face with fewer than 3 distinct vertices, or of no area.
    DegenerateFace { face: usize },
    /// A face whose vertices are not on one plane: the largest distance (m) of a vertex
    /// from the face's mean plane.
    NonPlanar { face: usize, distance: f64 },
    /// The faces do not close the block: the edge (a, b) is not walked once each way by
    /// two faces (a face missing, or a face whose vertices go the other way round from
    /// its neighbours').
    NotClosed { edge: (usize, usize) },
    /// Every face is clockwise seen from outside (the enclosed volume is negative).
    Inward,
    /// A vertex lies outside the plane of a face: the block is not convex (m: the
    /// vertex's distance in front of the plane).
    NonConvex {
        face: usize,
        vertex: usize,
        distance: f64,
    },
}

impl std::fmt::Display for PolyhedronDefect {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PolyhedronDefect::TooFew { vertices, faces } => write!(
                f,
                "{vertices} vertices and {faces} faces enclose no volume: a block needs at least 4 of each (a tetrahedron)"
            ),
            PolyhedronDefect::NotFinite { vertex } => {
                write!(f, "vertex {vertex} has a coordinate that is not a finite number")
            }
            PolyhedronDefect::BadIndex { face, index } => write!(
                f,
                "face {face} names vertex {index}, which does not exist (vertex indices are 0-based)"
            ),
            PolyhedronDefect::DegenerateFace { face } => write!(
                f,
                "face {face} has no area (fewer than 3 distinct vertices, or all on a line): remove it or give its corners"
            ),
            PolyhedronDefect::NonPlanar { face, distance } => write!(
                f,
                "face {face} is not planar: a vertex is {distance:.3e} m off its plane; split it into planar faces or move the vertex"
            ),
            PolyhedronDefect::NotClosed { edge: (a, b) } => write!(
                f,
                "the faces do not close the block at the edge from vertex {a} to vertex {b}: each edge must be walked once each way by two faces (a face is missing, or one is listed clockwise seen from outside: reverse its vertices)"
            ),
            PolyhedronDefect::Inward => write!(
                f,
                "every face is clockwise seen from outside: list each face's vertices counter-clockwise seen from outside (reverse them all)"
            ),
            PolyhedronDefect::NonConvex { face, vertex, distance } => write!(
                f,
                "the block is not convex: vertex {vertex} is {distance:.3e} m outside the plane of face {face}; split it into convex blocks"
            ),
        }
    }
}

/// The mass properties of a block of uniform density.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassProperties {
    /// Volume (m³).
    pub volume: f64,
    /// Centroid (m).
    pub centroid: Vec3,
    /// Second moments of volume about the centroid, ∫ (x − c)(x − c)ᵀ dV (m⁵); the inertia
    /// tensor of a block of density ρ is ρ (tr(C) I − C).
    pub second_moment: [[f64; 3]; 3],
}

impl MassProperties {
    /// The inertia tensor (kg·m²) about the centroid of the block with density `rho`
    /// (kg/m³): J = ρ (tr(C) I − C).
    pub fn inertia(&self, rho: f64) -> [[f64; 3]; 3] {
        let c = &self.second_moment;
        let tr = c[0][0] + c[1][1] + c[2][2];
        let mut j = [[0.0; 3]; 3];
        for (a, row) in j.iter_mut().enumerate() {
            for (b, v) in row.iter_mut().enumerate() {
                *v = rho * (if a == b { tr } else { 0.0 } - c[a][b]);
            }
        }
        j
    }
}

impl Polyhedron {
    /// The box between the corners `lo` and `hi` (m), its faces outward.
    pub fn from_box(lo: Vec3, hi: Vec3) -> Polyhedron {
        let v = |i: usize| {
            [
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            ]
        };
        Polyhedron {
            vertices: (0..8).map(v).collect(),
            faces: vec![
                vec![0, 2, 3, 1], // z = lo
                vec![4, 5, 7, 6], // z = hi
                vec![0, 1, 5, 4], // y = lo
                vec![2, 6, 7, 3], // y = hi
                vec![0, 4, 6, 2], // x = lo
                vec![1, 3, 7, 5], // x = hi
            ],
        }
    }

    /// The prism of the plane polygon `polygon` (m, counter-clockwise in (x, z): x to the
    /// right, z up, as a two-dimensional scene's (x, y)) between the depths y = `y0` and
    /// y = `y1` > `y0` (m): a two-dimensional block made solid, with its front face
    /// (y = y0), its back face and one face per edge.
    pub fn prism(polygon: &[[f64; 2]], y0: f64, y1: f64) -> Polyhedron {
        let n = polygon.len();
        let mut vertices: Vec<Vec3> = polygon.iter().map(|p| [p[0], y0, p[1]]).collect();
        vertices.extend(polygon.iter().map(|p| [p[0], y1, p[1]]));
        // seen from −y, x is to the right and z up: the front face keeps the polygon's
        // order, the back face (seen from +y) reverses it
        let mut faces = vec![(0..n).collect::<Vec<_>>(), (n..2 * n).rev().collect()];
        for i in 0..n {
            let j = (i + 1) % n;
            faces.push(vec![j, i, i + n, j + n]);
        }
        Polyhedron { vertices, faces }
    }

    /// The face's vertices (m).
    pub fn face_points(&self, face: usize) -> Vec<Vec3> {
        self.faces[face].iter().map(|&i| self.vertices[i]).collect()
    }

    /// The face's area vector by Newell's method: its outward normal times its area (m²),
    /// exact for a planar polygon.
    pub fn area_vector(&self, face: usize) -> Vec3 {
        area_vector(&self.face_points(face))
    }

    /// The face's plane: its unit outward normal and the mean of its vertices (m).
    pub fn plane(&self, face: usize) -> (Vec3, Vec3) {
        let p = self.face_points(face);
        let a = area_vector(&p);
        (scale3(a, 1.0 / norm3(a)), mean(&p))
    }

    /// The largest extent of the block (m): the diagonal of its bounding box.
    pub fn size(&self) -> f64 {
        let (lo, hi) = self.bounding_box();
        norm3(sub3(hi, lo))
    }

    /// The axis-aligned bounding box (lowest and highest corner, m): the broad phase of the
    /// contact search pairs the blocks whose boxes overlap.
    pub fn bounding_box(&self) -> (Vec3, Vec3) {
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for v in &self.vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        (lo, hi)
    }

    /// Check that this is a closed convex polyhedron with planar faces counter-clockwise
    /// seen from outside, to within `tol` (m; e.g. 10⁻⁹ of the block's size). The first
    /// defect found.
    pub fn check(&self, tol: f64) -> Result<(), PolyhedronDefect> {
        let (nv, nf) = (self.vertices.len(), self.faces.len());
        if nv < 4 || nf < 4 {
            return Err(PolyhedronDefect::TooFew {
                vertices: nv,
                faces: nf,
            });
        }
        if let Some(vertex) = self
            .vertices
            .iter()
            .position(|v| v.iter().any(|x| !x.is_finite()))
        {
            return Err(PolyhedronDefect::NotFinite { vertex });
        }
        for (face, f) in self.faces.iter().enumerate() {
            if let Some(&index) = f.iter().find(|&&i| i >= nv) {
                return Err(PolyhedronDefect::BadIndex { face, index });
            }
            let a = self.area_vector(face);
            let size = self.size();
            if f.len() < 3 || norm3(a) <= tol * size {
                return Err(PolyhedronDefect::DegenerateFace { face });
            }
            let (n, c) = self.plane(face);
            let distance = f
                .iter()
                .map(|&i| dot3(n, sub3(self.vertices[i], c)).abs())
                .fold(0.0, f64::max);
            if distance > tol {
                return Err(PolyhedronDefect::NonPlanar { face, distance });
            }
        }
        // every directed edge once, and its reverse once
        let mut edges = std::collections::BTreeMap::<(usize, usize), usize>::new();
        for f in &self.faces {
            for (k, &a) in f.iter().enumerate() {
                *edges.entry((a, f[(k + 1) % f.len()])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &count) in &edges {
            if count != 1 || edges.get(&(b, a)) != Some(&1) {
                return Err(PolyhedronDefect::NotClosed { edge: (a, b) });
            }
        }
        if self.mass_properties().volume <= 0.0 {
            return Err(PolyhedronDefect::Inward);
        }
        for face in 0..nf {
            let (n, c) = self.plane(face);
            for (vertex, &v) in self.vertices.iter().enumerate() {
                let distance = dot3(n, sub3(v, c));
                if distance > tol {
                    return Err(PolyhedronDefect::NonConvex {
                        face,
                        vertex,
                        distance,
                    });
                }
            }
        }
        Ok(())
    }

    /// Volume, centroid and second moments of volume, by the divergence theorem over the
    /// tetrahedra (o, a, b, c) of each face's fan, o the mean of the vertices: a
    /// tetrahedron of signed volume V = det[a−o, b−o, c−o]/6 has ∫ x dV = V (o+a+b+c)/4
    /// and ∫ x xᵀ dV = V/20 (Σ pᵢpᵢᵀ + s sᵀ), s = Σ pᵢ over its four corners pᵢ (taken
    /// relative to o). Negative volume: faces clockwise seen from outside.
    pub fn mass_properties(&self) -> MassProperties {
        let o = mean(&self.vertices);
        let mut volume = 0.0;
        let mut first = [0.0; 3];
        let mut second = [[0.0; 3]; 3];
        for f in &self.faces {
            let a = sub3(self.vertices[f[0]], o);
            for k in 1..f.len().saturating_sub(1) {
                let b = sub3(self.vertices[f[k]], o);
                let c = sub3(self.vertices[f[k + 1]], o);
                let v = dot3(a, cross3(b, c)) / 6.0;
                volume += v;
                let s = add3(add3(a, b), c);
                for i in 0..3 {
                    first[i] += v * s[i] / 4.0;
                    for j in 0..3 {
                        second[i][j] +=
                            v / 20.0 * (a[i] * a[j] + b[i] * b[j] + c[i] * c[j] + s[i] * s[j]);
                    }
                }
            }
        }
        // shift to the centroid: ∫ (x − c)(x − c)ᵀ = ∫ x xᵀ − V c cᵀ, c relative to o
        let c = if volume != 0.0 {
            scale3(first, 1.0 / volume)
        } else {
            [0.0; 3]
        };
        for i in 0..3 {
            for j in 0..3 {
                second[i][j] -= volume * c[i] * c[j];
            }
        }
        MassProperties {
            volume,
            centroid: add3(o, c),
            second_moment: second,
        }
    }
}

/// The mean of points (m).
pub fn mean(p: &[Vec3]) -> Vec3 {
    let s = p.iter().fold([0.0; 3], |s, &v| add3(s, v));
    scale3(s, 1.0 / p.len().max(1) as f64)
}

/// The area vector of a polygon in space by Newell's method (m²): normal times area,
/// by the right-hand rule of the vertices' order.
pub fn area_vector(p: &[Vec3]) -> Vec3 {
    let mut a = [0.0; 3];
    for (k, &u) in p.iter().enumerate() {
        let w = p[(k + 1) % p.len()];
        a[0] += (u[1] - w[1]) * (u[2] + w[2]);
        a[1] += (u[2] - w[2]) * (u[0] + w[0]);
        a[2] += (u[0] - w[0]) * (u[1] + w[1]);
    }
    scale3(a, 0.5)
}
