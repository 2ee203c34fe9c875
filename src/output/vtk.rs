//! ParaView files: one `.vtu` of the blocks (triangles of deformable blocks, polygons of
//! rigid and fixed blocks) and one of the contacts (line cells) per step, and a `.pvd`
//! collection. ASCII XML: small, dependable, readable by ParaView, meshio and VTK.

use super::write_atomic;
use crate::analysis::Outcome;
use crate::mesh::{BlockDofs, Mesh};
use crate::scene::Scene;
use crate::Result;
use std::fmt::Write;
use std::path::Path;

const VTK_LINE: u8 = 3;
const VTK_TRIANGLE: u8 = 5;
const VTK_POLYGON: u8 = 7;

/// The values as text: each the shortest decimal that reads back as the same f64
/// (zmij; "NaN", "inf" and "-inf" for the values that are not finite), space-separated.
fn data_array(s: &mut String, name: &str, comps: usize, vals: impl Iterator<Item = f64>) {
    let _ = write!(s, "<DataArray type=\"Float64\" Name=\"{name}\" NumberOfComponents=\"{comps}\" format=\"ascii\">");
    let mut buf = zmij::Buffer::new();
    for v in vals {
        s.push_str(buf.format(v));
        s.push(' ');
    }
    s.push_str("</DataArray>\n");
}

fn int_array(s: &mut String, ty: &str, name: &str, vals: impl Iterator<Item = i64>) {
    let _ = write!(
        s,
        "<DataArray type=\"{ty}\" Name=\"{name}\" format=\"ascii\">"
    );
    let mut buf = itoa::Buffer::new();
    for v in vals {
        s.push_str(buf.format(v));
        s.push(' ');
    }
    s.push_str("</DataArray>\n");
}

fn piece(s: &mut String, points: &[[f64; 2]], cells: &[Vec<u32>], types: &[u8]) {
    let _ = writeln!(
        s,
        "<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">",
        points.len(),
        cells.len()
    );
    s.push_str("<Points>\n");
    data_array(
        s,
        "Points",
        3,
        points.iter().flat_map(|p| [p[0], p[1], 0.0]),
    );
    s.push_str("</Points>\n<Cells>\n");
    int_array(
        s,
        "Int64",
        "connectivity",
        cells.iter().flatten().map(|&n| n as i64),
    );
    let mut off = 0i64;
    int_array(
        s,
        "Int64",
        "offsets",
        cells.iter().map(|c| {
            off += c.len() as i64;
            off
        }),
    );
    int_array(s, "UInt8", "types", types.iter().map(|&t| t as i64));
    s.push_str("</Cells>\n");
}

const HEAD: &str = "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n";
const TAIL: &str = "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";

/// Write `blocks_NNNN.vtu` and `contacts_NNNN.vtu` for one step.
pub fn write_step(
    dir: &Path,
    step: usize,
    _time: f64,
    scene: &Scene,
    mesh: &Mesh,
    out: &Outcome,
) -> Result<()> {
    let disp = &out.node_disp;
    let stress = out.stress.clone();
    // cells: triangles of deformable blocks, then one polygon per rigid or fixed block
    let mut cells: Vec<Vec<u32>> = mesh.triangles.iter().map(|t| t.to_vec()).collect();
    let mut types = vec![VTK_TRIANGLE; cells.len()];
    let mut cell_block: Vec<u32> = mesh.tri_block.clone();
    let mut cell_stress: Vec<[f64; 3]> = stress;
    for (i, b) in mesh.blocks.iter().enumerate() {
        if b.dofs != BlockDofs::Deformable {
            cells.push(b.boundary.clone());
            types.push(VTK_POLYGON);
            cell_block.push(i as u32);
            cell_stress.push([0.0; 3]);
        }
    }
    let mut s = String::from(HEAD);
    piece(&mut s, &mesh.nodes, &cells, &types);
    s.push_str("<PointData Vectors=\"displacement_m\">\n");
    data_array(
        &mut s,
        "displacement_m",
        3,
        disp.iter().flat_map(|d| [d[0], d[1], 0.0]),
    );
    s.push_str("</PointData>\n<CellData>\n");
    data_array(&mut s, "stress_Pa", 3, cell_stress.iter().flat_map(|x| *x));
    int_array(
        &mut s,
        "Int32",
        "block",
        cell_block.iter().map(|&b| b as i64),
    );
    int_array(
        &mut s,
        "Int32",
        "fixed",
        cell_block
            .iter()
            .map(|&b| (mesh.blocks[b as usize].dofs == BlockDofs::Fixed) as i64),
    );
    s.push_str("</CellData>\n");
    s.push_str(TAIL);
    write_atomic(&dir.join(format!("blocks_{step:04}.vtu")), s.as_bytes())?;

    // contacts: a line cell from point l to node m (coincident at the start), those of
    // the current configuration (a dynamic run adds and drops contacts)
    let contacts = out.current.as_ref().map_or(&mesh.contacts, |m| &m.contacts);
    let mut pts = Vec::with_capacity(2 * contacts.len());
    let mut cdisp = Vec::with_capacity(2 * contacts.len());
    let mut ccells = Vec::with_capacity(contacts.len());
    for (k, c) in contacts.iter().enumerate() {
        pts.push(c.at_l(|n| mesh.nodes[n as usize]));
        pts.push(mesh.nodes[c.node_m as usize]);
        cdisp.push(c.at_l(|n| disp[n as usize]));
        cdisp.push(disp[c.node_m as usize]);
        ccells.push(vec![2 * k as u32, 2 * k as u32 + 1]);
    }
    let mut s = String::from(HEAD);
    piece(&mut s, &pts, &ccells, &vec![VTK_LINE; ccells.len()]);
    s.push_str("<PointData Vectors=\"displacement_m\">\n");
    data_array(
        &mut s,
        "displacement_m",
        3,
        cdisp.iter().flat_map(|d| [d[0], d[1], 0.0]),
    );
    s.push_str("</PointData>\n<CellData>\n");
    data_array(
        &mut s,
        "normal_force_N",
        1,
        out.contact_forces.iter().map(|f| f[0]),
    );
    data_array(
        &mut s,
        "shear_force_N",
        1,
        out.contact_forces.iter().map(|f| f[1]),
    );
    data_array(
        &mut s,
        "normal",
        3,
        contacts
            .iter()
            .flat_map(|c| [c.normal[0], c.normal[1], 0.0]),
    );
    data_array(
        &mut s,
        "area_m2",
        1,
        contacts.iter().map(|c| c.length * scene.model.thickness),
    );
    int_array(
        &mut s,
        "Int32",
        "state_0stick_1slip_2open",
        out.contact_states.iter().map(|st| st.code() as i64),
    );
    // the laws' history (Outcome::contact_history): what each contact went through
    data_array(
        &mut s,
        "fracture_energy_spent",
        1,
        out.contact_history.iter().map(|h| h[0]),
    );
    data_array(
        &mut s,
        "cap_plastic_displacement_m",
        1,
        out.contact_history.iter().map(|h| h[1]),
    );
    s.push_str("</CellData>\n");
    s.push_str(TAIL);
    write_atomic(&dir.join(format!("contacts_{step:04}.vtu")), s.as_bytes())
}

/// Write `results.pvd`, the collection of the steps written (time, step number).
pub fn write_pvd(dir: &Path, steps: &[(f64, usize)]) -> Result<()> {
    let mut s = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n<Collection>\n",
    );
    for &(t, k) in steps {
        let _ = writeln!(
            s,
            "<DataSet timestep=\"{t:e}\" part=\"0\" file=\"blocks_{k:04}.vtu\"/>"
        );
        let _ = writeln!(
            s,
            "<DataSet timestep=\"{t:e}\" part=\"1\" file=\"contacts_{k:04}.vtu\"/>"
        );
    }
    s.push_str("</Collection>\n</VTKFile>\n");
    write_atomic(&dir.join("results.pvd"), s.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The text of the data arrays reads back as the same values, to the bit: the
    /// shortest round-trip decimals of zmij, parsed by the reader the checks use.
    #[test]
    fn arrays_read_back_to_the_bit() {
        let vals = [
            0.1 + 0.2,
            -0.0,
            0.7000000000000001,
            1e-300,
            f64::MIN_POSITIVE,
            5e-324,
            f64::MAX,
            -1.234_567_890_123_456_7e-7,
            3.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let points: Vec<[f64; 2]> = vals.chunks(2).map(|c| [c[0], c[1]]).collect();
        let cells = vec![vec![0, 1, 2], vec![3, 4, 5], vec![0, 5]];
        let mut s = String::from(HEAD);
        piece(
            &mut s,
            &points,
            &cells,
            &[VTK_TRIANGLE, VTK_TRIANGLE, VTK_LINE],
        );
        s.push_str("<PointData>\n");
        data_array(&mut s, "x", 1, vals.iter().copied());
        s.push_str("</PointData>\n");
        s.push_str(TAIL);
        let path = Path::new("test.vtu");
        let vtu = crate::output::read::Vtu::parse(&s, path).unwrap();
        let back = vtu.array("x", path).unwrap();
        assert_eq!(back.len(), vals.len());
        for (a, b) in vals.iter().zip(back) {
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{a} read as {b}"
            );
        }
        let p = vtu.points(path).unwrap();
        for (a, b) in points.iter().zip(&p) {
            for c in 0..2 {
                assert!(a[c].to_bits() == b[c].to_bits() || (a[c].is_nan() && b[c].is_nan()));
            }
        }
        assert_eq!(vtu.cells(points.len(), path).unwrap(), cells);
    }
}
