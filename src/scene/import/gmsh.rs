//! Gmsh `.msh` meshes, ASCII format 4.1 or 2.2 (Gmsh reference manual, section "MSH file
//! format"): every surface entity (elementary surface) becomes one block whose outline is
//! the boundary of its triangles and quadrangles ([`super::outline`]); its group is the
//! name of the surface's physical group.
//!
//! Only the sections `$MeshFormat`, `$PhysicalNames`, `$Entities`, `$Nodes` and
//! `$Elements` are read; the others are skipped. Higher-order elements contribute their
//! corner nodes (the outline is drawn with straight edges). Nodes must lie in a plane
//! z = constant; x and y are the scene's coordinates (m).
//!
//! A small reader of our own rather than the `mshio` crate: mshio reads format 4.1 only
//! (Gmsh still writes 2.2 on request, and other tools write it by default), its errors do
//! not give the line of the file, and it depends on nom 5.

use super::outline::{outline, OutlineDefect};
use super::{name_blocks, tidy, ImportError, ImportedBlock};
use std::collections::HashMap;

type R<T> = Result<T, ImportError>;

/// Relative tolerance (of a block's size) under which outline vertices are merged or
/// dropped as collinear: Gmsh writes coordinates to 16 significant digits, so mesh nodes
/// on a straight edge are collinear to about 1e-15; 1e-9 leaves a wide margin and keeps
/// any corner a drawing would make.
const COLLINEAR: f64 = 1e-9;

/// One section of the file: its name, the line of its `$Name` header and its body lines
/// (1-based line number, text), blank lines left out.
struct Section<'a> {
    name: &'a str,
    line: usize,
    body: Vec<(usize, &'a str)>,
}

fn sections(text: &str) -> R<Vec<Section<'_>>> {
    let mut out = Vec::new();
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim()));
    while let Some((n, l)) = lines.next() {
        if l.is_empty() {
            continue;
        }
        let Some(name) = l.strip_prefix('$') else {
            return Err(ImportError::new(
                Some(n),
                format!("'{}' is outside any $Section", short(l)),
                "a .msh file is made of sections $Name ... $EndName; save the mesh again from Gmsh",
            ));
        };
        let end = format!("$End{name}");
        let mut body = Vec::new();
        let mut closed = false;
        for (m, b) in lines.by_ref() {
            if b == end {
                closed = true;
                break;
            }
            if !b.is_empty() {
                body.push((m, b));
            }
        }
        if !closed {
            return Err(ImportError::new(
                Some(n),
                format!("the section ${name} has no {end}"),
                format!("the file is cut short: add {end} or save the mesh again"),
            ));
        }
        out.push(Section {
            name,
            line: n,
            body,
        });
    }
    Ok(out)
}

fn short(s: &str) -> String {
    s.chars().take(40).collect()
}

/// Body lines read in order, with the line numbers for errors.
struct Cursor<'a> {
    sec: &'a Section<'a>,
    at: usize,
}

impl<'a> Cursor<'a> {
    fn new(sec: &'a Section<'a>) -> Self {
        Cursor { sec, at: 0 }
    }
    /// The next line's number and its whitespace-separated fields.
    fn next(&mut self, what: &str) -> R<(usize, Vec<&'a str>)> {
        match self.sec.body.get(self.at) {
            Some(&(n, l)) => {
                self.at += 1;
                Ok((n, l.split_whitespace().collect()))
            }
            None => Err(ImportError::new(
                Some(self.sec.line),
                format!("the section ${} ends before {what}", self.sec.name),
                "the section is incomplete: save the mesh again from Gmsh",
            )),
        }
    }
    fn rest(&self) -> Option<usize> {
        self.sec.body.get(self.at).map(|b| b.0)
    }
}

/// Field `i` of a line as a number of type T.
fn field<T: std::str::FromStr>(f: &[&str], i: usize, line: usize, what: &str) -> R<T> {
    let s = f.get(i).ok_or_else(|| {
        ImportError::new(
            Some(line),
            format!("the line has {} fields; {what} is missing", f.len()),
            "complete the line (see the MSH format in the Gmsh manual) or save the mesh again",
        )
    })?;
    s.parse().map_err(|_| {
        ImportError::new(
            Some(line),
            format!("'{}' is not a valid {what}", short(s)),
            "correct the number, or save the mesh again from Gmsh",
        )
    })
}

/// A surface's corner-node elements, the line where they start and its physical tag.
struct Surface {
    line: usize,
    physical: Option<i64>,
    elements: Vec<Vec<u64>>,
}

/// Number of corner nodes of a 2D element type (triangles of any order: 3; quadrangles:
/// 4); `None` for other types.
fn corners(element_type: i64) -> Option<usize> {
    match element_type {
        2 | 9 | 20 | 21 | 22 | 23 | 24 | 25 => Some(3),
        3 | 10 | 16 | 36 | 37 | 38 | 39 => Some(4),
        _ => None,
    }
}

/// Read the blocks of a Gmsh mesh (text of the whole file).
pub fn read(text: &str) -> R<Vec<ImportedBlock>> {
    let secs = sections(text)?;
    let fmt = secs
        .iter()
        .find(|s| s.name == "MeshFormat")
        .ok_or_else(|| {
            ImportError::new(
                Some(1),
                "there is no $MeshFormat section: this is not a Gmsh .msh file",
                "export the mesh from Gmsh in MSH format (4.1 or 2.2, ASCII)",
            )
        })?;
    let (fl, f) = Cursor::new(fmt).next("the version")?;
    let version: f64 = field(&f, 0, fl, "format version")?;
    let file_type: i64 = field(&f, 1, fl, "file type")?;
    if file_type != 0 {
        return Err(ImportError::new(
            Some(fl),
            "the mesh is binary",
            "save it as ASCII (Gmsh: Mesh.Binary = 0, or uncheck 'Save in binary format')",
        ));
    }
    let v4 = if (4.1..4.2).contains(&version) {
        true
    } else if (2.0..2.3).contains(&version) {
        false
    } else {
        return Err(ImportError::new(
            Some(fl),
            format!("MSH format version {version} is not read"),
            "save the mesh in format 4.1 or 2.2 (Gmsh: Mesh.MshFileVersion = 4.1, or File > Export > Version 4 ASCII)",
        ));
    };
    let mut names: HashMap<i64, String> = HashMap::new();
    if let Some(s) = secs.iter().find(|s| s.name == "PhysicalNames") {
        let mut c = Cursor::new(s);
        let (l, f) = c.next("the number of names")?;
        let n: usize = field(&f, 0, l, "number of physical names")?;
        for _ in 0..n {
            let (l, f) = c.next("all the physical names")?;
            let dim: i64 = field(&f, 0, l, "dimension")?;
            let tag: i64 = field(&f, 1, l, "physical tag")?;
            let name = f[2..].join(" ");
            let name = name.trim_matches('"');
            if dim == 2 && !name.is_empty() {
                names.insert(tag, name.to_string());
            }
        }
    }
    let nodes_sec = secs.iter().find(|s| s.name == "Nodes").ok_or_else(|| {
        ImportError::new(
            Some(fmt.line),
            "there is no $Nodes section",
            "mesh the geometry (Gmsh: Mesh > 2D) before saving",
        )
    })?;
    let elems_sec = secs.iter().find(|s| s.name == "Elements").ok_or_else(|| {
        ImportError::new(
            Some(nodes_sec.line),
            "there is no $Elements section",
            "mesh the geometry (Gmsh: Mesh > 2D) before saving",
        )
    })?;
    let (xyz, surfaces) = if v4 {
        let phys = match secs.iter().find(|s| s.name == "Entities") {
            Some(s) => surface_physicals_v4(s)?,
            None => HashMap::new(),
        };
        let xyz = nodes_v4(nodes_sec)?;
        (xyz, elements_v4(elems_sec, &phys)?)
    } else {
        (nodes_v2(nodes_sec)?, elements_v2(elems_sec)?)
    };
    if surfaces.is_empty() {
        return Err(ImportError::new(
            Some(elems_sec.line),
            "the mesh has no triangles or quadrangles",
            "mesh the surfaces in 2D (Gmsh: Mesh > 2D) and save again",
        ));
    }
    // the plane z = constant
    let used: Vec<[f64; 3]> = surfaces
        .iter()
        .flat_map(|s| s.1.elements.iter().flatten())
        .filter_map(|n| xyz.get(n).map(|p| p.1))
        .collect();
    if let Some(first) = used.first() {
        let xy: Vec<[f64; 2]> = used.iter().map(|p| [p[0], p[1]]).collect();
        let size = crate::geometry::polygon::size(&xy).max(f64::MIN_POSITIVE);
        if let Some(p) = used.iter().find(|p| (p[2] - first[2]).abs() > 1e-9 * size) {
            let line = xyz.values().find(|q| q.1 == *p).map(|q| q.0);
            return Err(ImportError::new(
                line,
                format!(
                    "the mesh is not flat: a node has z = {} and another z = {}",
                    p[2], first[2]
                ),
                "draw the blocks in a plane z = constant (dfem is 2D: x and y are used)",
            ));
        }
    }
    let xy: HashMap<u64, [f64; 2]> = xyz.iter().map(|(k, v)| (*k, [v.1[0], v.1[1]])).collect();
    let mut out = Vec::new();
    for (tag, s) in &surfaces {
        let ring = outline(&s.elements, &xy).map_err(|d| {
            let (what, fix) = d.explain();
            let what = match d {
                OutlineDefect::MissingNode(_) => what,
                _ => format!("surface {tag}: {what}"),
            };
            ImportError::new(Some(s.line), what, fix)
        })?;
        let ring = tidy(ring, COLLINEAR).ok_or_else(|| {
            ImportError::new(
                Some(s.line),
                format!("surface {tag} has a flat outline"),
                "remesh the surface",
            )
        })?;
        let group = match s.physical {
            None => "surface".to_string(),
            Some(p) => names
                .get(&p)
                .cloned()
                .unwrap_or_else(|| format!("physical_{p}")),
        };
        out.push((group, ring));
    }
    Ok(name_blocks(out))
}

/// `$Entities` (4.1): surface tag → its physical tag (`None` if none). A surface in two
/// physical groups is an error (its material would be ambiguous).
fn surface_physicals_v4(s: &Section) -> R<HashMap<i64, Option<i64>>> {
    let mut c = Cursor::new(s);
    let (l, f) = c.next("the entity counts")?;
    let counts: Vec<usize> = (0..4)
        .map(|i| field(&f, i, l, "entity count"))
        .collect::<R<_>>()?;
    for _ in 0..counts[0] + counts[1] {
        c.next("all the points and curves")?;
    }
    let mut out = HashMap::new();
    for _ in 0..counts[2] {
        let (l, f) = c.next("all the surfaces")?;
        let tag: i64 = field(&f, 0, l, "surface tag")?;
        let np: usize = field(&f, 7, l, "number of physical tags")?;
        let tags: Vec<i64> = (0..np)
            .map(|i| field::<i64>(&f, 8 + i, l, "physical tag").map(i64::abs))
            .collect::<R<_>>()?;
        if tags.len() > 1 {
            return Err(ImportError::new(
                Some(l),
                format!(
                    "surface {tag} is in {} physical groups ({tags:?})",
                    tags.len()
                ),
                "put each surface in one physical surface group (its group gives its material)",
            ));
        }
        out.insert(tag, tags.first().copied());
    }
    Ok(out)
}

/// Node tag → (line, [x, y, z]).
type Nodes = HashMap<u64, (usize, [f64; 3])>;

fn xyz_of(f: &[&str], from: usize, l: usize) -> R<[f64; 3]> {
    let mut p = [0.0; 3];
    for (k, q) in p.iter_mut().enumerate() {
        *q = field::<f64>(f, from + k, l, "coordinate")?;
        if !q.is_finite() {
            return Err(ImportError::new(
                Some(l),
                "a coordinate is not finite",
                "give finite coordinates in m",
            ));
        }
    }
    Ok(p)
}

fn nodes_v4(s: &Section) -> R<Nodes> {
    let mut c = Cursor::new(s);
    let (l, f) = c.next("the node counts")?;
    let blocks: usize = field(&f, 0, l, "number of entity blocks")?;
    let mut out = Nodes::new();
    for _ in 0..blocks {
        let (l, f) = c.next("all the node blocks")?;
        let dim: usize = field(&f, 0, l, "entity dimension")?;
        let parametric: u8 = field(&f, 2, l, "parametric flag")?;
        let n: usize = field(&f, 3, l, "number of nodes in the block")?;
        let mut tags = Vec::with_capacity(n);
        for _ in 0..n {
            let (l, f) = c.next("all the node tags of a block")?;
            tags.push(field::<u64>(&f, 0, l, "node tag")?);
        }
        let extra = if parametric == 1 { dim.min(3) } else { 0 };
        for t in tags {
            let (l, f) = c.next("all the node coordinates of a block")?;
            if f.len() != 3 + extra {
                return Err(ImportError::new(
                    Some(l),
                    format!("a node's line has {} fields, not {}", f.len(), 3 + extra),
                    "give x y z (and the parametric coordinates when the block's flag is 1)",
                ));
            }
            out.insert(t, (l, xyz_of(&f, 0, l)?));
        }
    }
    if let Some(l) = c.rest() {
        return Err(ImportError::new(
            Some(l),
            "more nodes than the section's counts say",
            "correct the counts on the first line of $Nodes, or save the mesh again",
        ));
    }
    Ok(out)
}

fn nodes_v2(s: &Section) -> R<Nodes> {
    let mut c = Cursor::new(s);
    let (l, f) = c.next("the number of nodes")?;
    let n: usize = field(&f, 0, l, "number of nodes")?;
    let mut out = Nodes::new();
    for _ in 0..n {
        let (l, f) = c.next("all the nodes")?;
        let t: u64 = field(&f, 0, l, "node tag")?;
        out.insert(t, (l, xyz_of(&f, 1, l)?));
    }
    Ok(out)
}

/// The node tags of one element line from field `from`, corners only.
fn element_nodes(f: &[&str], from: usize, corners: usize, l: usize) -> R<Vec<u64>> {
    (0..corners)
        .map(|k| field(f, from + k, l, "node tag"))
        .collect()
}

fn elements_v4(s: &Section, phys: &HashMap<i64, Option<i64>>) -> R<Vec<(i64, Surface)>> {
    let mut c = Cursor::new(s);
    let (l, f) = c.next("the element counts")?;
    let blocks: usize = field(&f, 0, l, "number of entity blocks")?;
    let mut out: Vec<(i64, Surface)> = Vec::new();
    for _ in 0..blocks {
        let (l, f) = c.next("all the element blocks")?;
        let dim: i64 = field(&f, 0, l, "entity dimension")?;
        let tag: i64 = field(&f, 1, l, "entity tag")?;
        let ty: i64 = field(&f, 2, l, "element type")?;
        let n: usize = field(&f, 3, l, "number of elements in the block")?;
        let k = if dim == 2 { corners(ty) } else { None };
        let idx = match k {
            Some(_) => match out.iter().position(|s| s.0 == tag) {
                Some(i) => Some(i),
                None => {
                    out.push((
                        tag,
                        Surface {
                            line: l,
                            physical: phys.get(&tag).copied().flatten(),
                            elements: Vec::new(),
                        },
                    ));
                    Some(out.len() - 1)
                }
            },
            None => None,
        };
        for _ in 0..n {
            let (el, ef) = c.next("all the elements of a block")?;
            if let (Some(k), Some(i)) = (k, idx) {
                let nodes = element_nodes(&ef, 1, k, el)?;
                out[i].1.elements.push(nodes);
            }
        }
    }
    Ok(out)
}

fn elements_v2(s: &Section) -> R<Vec<(i64, Surface)>> {
    let mut c = Cursor::new(s);
    let (l, f) = c.next("the number of elements")?;
    let n: usize = field(&f, 0, l, "number of elements")?;
    let mut out: Vec<(i64, Surface)> = Vec::new();
    for _ in 0..n {
        let (l, f) = c.next("all the elements")?;
        let ty: i64 = field(&f, 1, l, "element type")?;
        let ntags: usize = field(&f, 2, l, "number of tags")?;
        let Some(k) = corners(ty) else { continue };
        if ntags < 2 {
            return Err(ImportError::new(
                Some(l),
                "the element has no elementary (surface) tag",
                "save the mesh with its physical and elementary tags (Gmsh writes both)",
            ));
        }
        let physical: i64 = field(&f, 3, l, "physical tag")?;
        let tag: i64 = field(&f, 4, l, "elementary tag")?;
        let nodes = element_nodes(&f, 3 + ntags, k, l)?;
        let i = match out.iter().position(|s| s.0 == tag) {
            Some(i) => i,
            None => {
                out.push((
                    tag,
                    Surface {
                        line: l,
                        physical: (physical != 0).then_some(physical),
                        elements: Vec::new(),
                    },
                ));
                out.len() - 1
            }
        };
        out[i].1.elements.push(nodes);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two unit squares side by side, format 2.2, physical groups "left" (1) and 2 without
    /// a name; each square is two triangles.
    const V22: &str = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n2 1 \"left\"\n$EndPhysicalNames\n$Nodes\n6\n1 0 0 0\n2 1 0 0\n3 2 0 0\n4 0 1 0\n5 1 1 0\n6 2 1 0\n$EndNodes\n$Elements\n5\n1 1 2 0 9 1 2\n2 2 2 1 10 1 2 5\n3 2 2 1 10 1 5 4\n4 2 2 2 11 2 3 6\n5 2 2 2 11 2 6 5\n$EndElements\n";

    #[test]
    fn format_2_2_surfaces_become_blocks() {
        let b = read(V22).unwrap();
        assert_eq!(b.len(), 2);
        assert_eq!(
            (b[0].name.as_str(), b[0].group.as_str()),
            ("left_1", "left")
        );
        assert_eq!(b[1].group, "physical_2");
        for (blk, x0) in b.iter().zip([0.0, 1.0]) {
            assert_eq!(blk.vertices.len(), 4);
            // exact: the shoelace sum of these small integers is exact in f64
            assert_eq!(crate::geometry::polygon::signed_area(&blk.vertices), 1.0);
            assert!(blk.vertices.iter().all(|p| p[0] == x0 || p[0] == x0 + 1.0));
        }
    }

    #[test]
    fn errors_name_the_line() {
        let bad = V22.replace("2 2 2 1 10 1 2 5", "2 2 2 1 10 1 2 x");
        let e = read(&bad).unwrap_err();
        assert_eq!(e.line, Some(20), "{e:?}");
        assert!(e.what.contains("'x'"), "{e:?}");
        let e = read(&V22.replace("2.2 0 8", "2.2 1 8")).unwrap_err();
        assert_eq!(e.line, Some(2));
        let e = read(&V22.replace("$EndNodes\n", "")).unwrap_err();
        assert!(e.what.contains("$EndNodes"), "{e:?}");
        let e = read(&V22.replace("6 2 1 0", "6 2 1 0.5")).unwrap_err();
        assert!(e.what.contains("not flat"), "{e:?}");
        assert_eq!(e.line, Some(15));
    }
}
