//! Hand-written declarations of MUMPS' C interface (`dmumps_c.h`, MUMPS 5.5, 32-bit
//! `MUMPS_INT`): the structure `DMUMPS_STRUC_C` and the one entry point `dmumps_c`.
//!
//! Hand-written rather than generated: the interface is one plain C structure and one
//! function, and its layout is checked at run time against the C compiler's
//! (`sizeof` and three `offsetof` from `csrc/shim.c`) before the first call, so a header of
//! another MUMPS version is reported instead of corrupting memory
//! ([`check_layout`]). No crate on crates.io wraps the system MUMPS (DEPENDENCIES.md).

use std::os::raw::{c_char, c_int};

/// `MUMPS_INT` (32 bits: Debian's MUMPS is built without `-DINTSIZE64`).
pub type MumpsInt = c_int;

/// `DMUMPS_STRUC_C`, field for field (MUMPS 5.5.1).
#[repr(C)]
pub struct DmumpsStrucC {
    pub sym: MumpsInt,
    pub par: MumpsInt,
    pub job: MumpsInt,
    pub comm_fortran: MumpsInt,
    pub icntl: [MumpsInt; 60],
    pub keep: [MumpsInt; 500],
    pub cntl: [f64; 15],
    pub dkeep: [f64; 230],
    pub keep8: [i64; 150],
    pub n: MumpsInt,
    pub nblk: MumpsInt,
    pub nz_alloc: MumpsInt,
    pub nz: MumpsInt,
    pub nnz: i64,
    pub irn: *mut MumpsInt,
    pub jcn: *mut MumpsInt,
    pub a: *mut f64,
    pub nz_loc: MumpsInt,
    pub nnz_loc: i64,
    pub irn_loc: *mut MumpsInt,
    pub jcn_loc: *mut MumpsInt,
    pub a_loc: *mut f64,
    pub nelt: MumpsInt,
    pub eltptr: *mut MumpsInt,
    pub eltvar: *mut MumpsInt,
    pub a_elt: *mut f64,
    pub blkptr: *mut MumpsInt,
    pub blkvar: *mut MumpsInt,
    pub perm_in: *mut MumpsInt,
    pub sym_perm: *mut MumpsInt,
    pub uns_perm: *mut MumpsInt,
    pub colsca: *mut f64,
    pub rowsca: *mut f64,
    pub colsca_from_mumps: MumpsInt,
    pub rowsca_from_mumps: MumpsInt,
    pub rhs: *mut f64,
    pub redrhs: *mut f64,
    pub rhs_sparse: *mut f64,
    pub sol_loc: *mut f64,
    pub rhs_loc: *mut f64,
    pub irhs_sparse: *mut MumpsInt,
    pub irhs_ptr: *mut MumpsInt,
    pub isol_loc: *mut MumpsInt,
    pub irhs_loc: *mut MumpsInt,
    pub nrhs: MumpsInt,
    pub lrhs: MumpsInt,
    pub lredrhs: MumpsInt,
    pub nz_rhs: MumpsInt,
    pub lsol_loc: MumpsInt,
    pub nloc_rhs: MumpsInt,
    pub lrhs_loc: MumpsInt,
    pub schur_mloc: MumpsInt,
    pub schur_nloc: MumpsInt,
    pub schur_lld: MumpsInt,
    pub mblock: MumpsInt,
    pub nblock: MumpsInt,
    pub nprow: MumpsInt,
    pub npcol: MumpsInt,
    pub info: [MumpsInt; 80],
    pub infog: [MumpsInt; 80],
    pub rinfo: [f64; 40],
    pub rinfog: [f64; 40],
    pub deficiency: MumpsInt,
    pub pivnul_list: *mut MumpsInt,
    pub mapping: *mut MumpsInt,
    pub size_schur: MumpsInt,
    pub listvar_schur: *mut MumpsInt,
    pub schur: *mut f64,
    pub instance_number: MumpsInt,
    pub wk_user: *mut f64,
    pub version_number: [c_char; 32],
    pub ooc_tmpdir: [c_char; 256],
    pub ooc_prefix: [c_char; 64],
    pub write_problem: [c_char; 256],
    pub lwk_user: MumpsInt,
    pub save_dir: [c_char; 256],
    pub save_prefix: [c_char; 256],
    pub metis_options: [MumpsInt; 40],
}

extern "C" {
    /// The MUMPS driver: does what `job` says on the instance.
    pub fn dmumps_c(p: *mut DmumpsStrucC);
    fn dfem_dmumps_struc_size() -> usize;
    fn dfem_dmumps_offset_info() -> usize;
    fn dfem_dmumps_offset_pivnul_list() -> usize;
    fn dfem_dmumps_offset_metis_options() -> usize;
    /// Fortran communicator for `comm_fortran` (MPI_COMM_SELF; MPI initialized if needed).
    pub fn dfem_mumps_comm() -> c_int;
    /// Fortran communicator MPI_COMM_WORLD (MPI build, MPI started), for distributed runs.
    pub fn dfem_mumps_comm_world() -> c_int;
    /// OpenBLAS on one thread (a no-op with another BLAS).
    pub fn dfem_blas_single_thread();
}

/// Compares the Rust layout of [`DmumpsStrucC`] with the C compiler's on the installed
/// header; `Err` names the first mismatch.
pub fn check_layout() -> Result<(), String> {
    let s = std::mem::size_of::<DmumpsStrucC>();
    // SAFETY: plain functions returning sizeof/offsetof.
    let (cs, ci, cp, cm) = unsafe {
        (
            dfem_dmumps_struc_size(),
            dfem_dmumps_offset_info(),
            dfem_dmumps_offset_pivnul_list(),
            dfem_dmumps_offset_metis_options(),
        )
    };
    let checks = [
        ("sizeof(DMUMPS_STRUC_C)", s, cs),
        (
            "offsetof(info)",
            std::mem::offset_of!(DmumpsStrucC, info),
            ci,
        ),
        (
            "offsetof(pivnul_list)",
            std::mem::offset_of!(DmumpsStrucC, pivnul_list),
            cp,
        ),
        (
            "offsetof(metis_options)",
            std::mem::offset_of!(DmumpsStrucC, metis_options),
            cm,
        ),
    ];
    for (what, rust, c) in checks {
        if rust != c {
            return Err(format!(
                "the MUMPS header does not match this binding (written for MUMPS 5.5): {what} is {c} in C, {rust} here"
            ));
        }
    }
    Ok(())
}
