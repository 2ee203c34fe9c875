//! The bindgen output over `csrc/petsc.h` (see build.rs for why bindgen here): PETSc's
//! KSP, PC, Mat and Vec functions used by [`crate::petsc`], MPI_Comm_rank/size and the C
//! shim's MPI handles. PETSc's type `Vec` is re-exported as `PVec` (it would shadow Rust's).
#![allow(
    non_camel_case_types,
    non_snake_case,
    non_upper_case_globals,
    dead_code,
    improper_ctypes,
    unsafe_op_in_unsafe_fn,
    clippy::all
)]

mod generated {
    #![allow(
        non_camel_case_types,
        non_snake_case,
        non_upper_case_globals,
        dead_code,
        improper_ctypes,
        clippy::all
    )]
    include!(concat!(env!("OUT_DIR"), "/petsc_bindings.rs"));
}
pub use generated::Vec as PVec;
pub use generated::*;
