//! DXF drawings: every closed `LWPOLYLINE` or `POLYLINE` becomes one block; its group is
//! its layer. Read with the `dxf` crate (ixmilia/dxf-rs). Stub until the reader is written.

use super::{ImportError, ImportedBlock};

pub fn read(_bytes: &[u8]) -> Result<Vec<ImportedBlock>, ImportError> {
    Err(ImportError::new(
        None,
        "DXF is not read yet",
        "use a Gmsh mesh",
    ))
}
