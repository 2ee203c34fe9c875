//! PETSc's linear solvers (KSP: a Krylov method and a preconditioner) as a
//! [`LinearBackend`]. The matrix is an AIJ matrix (SeqAIJ on one process, MPIAIJ on
//! several) filled from dfem's CSR; the method is chosen in PETSc's options database, so
//! `--petsc-options "-ksp_type cg -pc_type gamg -pc_gamg_threshold 0.05"` (after the
//! `PETSC_OPTIONS` environment variable) reaches it unchanged. Each backend has its own
//! options database (`PetscOptionsCreate`, attached to its KSP), so the options of one
//! never leak into another. Defaults
//! ([`Petsc::new`]): conjugate gradients with smoothed-aggregation algebraic multigrid
//! (GAMG), relative tolerance [`DEFAULT_RTOL`] on the true (unpreconditioned) residual,
//! the matrix flagged symmetric positive definite; the rigid-body modes given by
//! [`LinearBackend::set_near_null_space`] become GAMG's near-null space
//! (`MatSetNearNullSpace`), orthonormalized.
//!
//! Phases: `analyze` creates the matrix with its pattern (preallocated from the CSR, so
//! setting values never allocates), `factorize` sets the values and sets up the
//! preconditioner (`KSPSetUp`: GAMG's hierarchy, or a factorization with
//! `-ksp_type preonly -pc_type cholesky`), `solve` runs `KSPSolve`. A solve that does
//! not converge is [`SolveError::NoConvergence`]; `stats().last_true_residual` is
//! ‖b − A x‖ / ‖b‖ recomputed here from dfem's copy of A.
//!
//! Distributed (feature `mpi`, under `mpirun`): every rank holds the same matrix (dfem
//! assembles each rank's rows on that rank and exchanges them, `dfem::assembly::Ranks`)
//! and calls the backend with the same arguments; the unknowns
//! are partitioned over the ranks by the partition given with
//! [`LinearBackend::set_partition`] (dfem's block partition, `dfem::solve::block_partition`:
//! whole blocks, cuts along joints — the subdomains of `faer-substructured` come from the
//! same function) or else by METIS on the node graph ([`dfem_kernels::metis_partition`],
//! whole nodes, few couplings cut), and renumbered so that each rank owns a contiguous
//! range of rows; each rank sets only its own rows of the MPIAIJ matrix and its own entries of the
//! right-hand side; the solution is gathered on every rank (`VecScatterCreateToAll`) and
//! returned in dfem's numbering. Without `mpi` each process solves alone (MPI_COMM_SELF).
//!
//! PETSc keeps global state (options, logging, error stack): calls are serialized by a
//! process-wide lock, and PETSc starts once per process (`PetscInitialize` with
//! `-no_signal_handler`, so Rust's handlers stay) and ends in [`finalize`].

use crate::petsc_sys as sys;
use dfem_kernels::{same_bits, CsrMatrix, CsrPattern, LinearBackend, SolveError, SolverStats};
use std::ffi::{c_char, c_int, CStr, CString};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

/// Default relative tolerance of the Krylov solve on ‖b − A x‖₂ / ‖b‖₂: well below the
/// out-of-balance tolerances of the analyses (≥ 1e-8, docs/theory.md §4), so that PETSc's
/// answers agree with the direct solvers' to about cond(A) × 1e-12.
pub const DEFAULT_RTOL: f64 = 1e-12;

/// Iteration limit of the default Krylov solve.
pub const DEFAULT_MAX_IT: i32 = 10_000;

static LOCK: Mutex<()> = Mutex::new(());
static INIT: OnceLock<Result<(), String>> = OnceLock::new();

fn petsc_err(code: sys::PetscErrorCode, what: &str) -> Result<(), SolveError> {
    if code == 0 {
        Ok(())
    } else {
        Err(SolveError::Other(format!(
            "PETSc error {code} in {what} (PETSc printed the details on standard error)"
        )))
    }
}

macro_rules! call {
    ($f:ident ( $($arg:expr),* $(,)? )) => {
        // SAFETY: every handle passed was created by PETSc and not yet destroyed, every
        // array has the length PETSc reads from it (see each call site).
        petsc_err(unsafe { sys::$f($($arg),*) }, stringify!($f))
    };
}

/// Starts PETSc (and MPI) once per process; later calls return the first outcome.
fn init() -> Result<(), SolveError> {
    INIT.get_or_init(|| {
        // SAFETY: sets OpenBLAS's thread count (deterministic sums, no spinning threads).
        unsafe { sys::dfem_blas_single_thread() };
        let mut flag: sys::PetscBool = sys::PetscBool_PETSC_FALSE;
        // SAFETY: queries a flag.
        unsafe { sys::PetscInitialized(&mut flag) };
        if flag == sys::PetscBool_PETSC_TRUE {
            return Ok(());
        }
        // argv: program name and -no_signal_handler; PETSc keeps the pointers, so leak them
        // (NULL-terminated, as C's argv)
        let mut args: Vec<*mut c_char> = ["dfem", "-no_signal_handler"]
            .iter()
            .map(|s| CString::new(*s).unwrap().into_raw())
            .collect();
        let argc: &'static mut c_int = Box::leak(Box::new(args.len() as c_int));
        args.push(std::ptr::null_mut());
        let argv: &'static mut Vec<*mut c_char> = Box::leak(Box::new(args));
        let argv_ptr: &'static mut *mut *mut c_char = Box::leak(Box::new(argv.as_mut_ptr()));
        // SAFETY: argc/argv live for the whole process, as PETSc requires.
        let code =
            unsafe { sys::PetscInitialize(argc, argv_ptr, std::ptr::null(), std::ptr::null()) };
        if code != 0 {
            return Err(format!("PetscInitialize failed with error {code}"));
        }
        Ok(())
    })
    .clone()
    .map_err(SolveError::Other)
}

/// The communicator of the solves: PETSC_COMM_WORLD with feature `mpi`, else MPI_COMM_SELF.
fn comm() -> sys::MPI_Comm {
    if cfg!(feature = "mpi") {
        // SAFETY: a global set by PetscInitialize (called before, in init).
        unsafe { sys::PETSC_COMM_WORLD }
    } else {
        // SAFETY: returns a constant handle.
        unsafe { sys::dfem_comm_self() }
    }
}

/// Rank of this process and number of processes of the solves (0 and 1 without `mpi`).
/// Starts PETSc (and MPI) on first use.
pub fn rank_and_size() -> Result<(usize, usize), SolveError> {
    init()?;
    let (mut r, mut s) = (0 as c_int, 1 as c_int);
    let c = comm();
    // SAFETY: valid communicator, output integers.
    unsafe {
        sys::MPI_Comm_rank(c, &mut r);
        sys::MPI_Comm_size(c, &mut s);
    }
    Ok((r as usize, s as usize))
}

/// Concatenates the `local` values of every rank, in rank order, into `out` on every rank
/// (`MPI_Allgatherv` on the communicator of the solves): rank r contributes `counts[r]`
/// values (`counts[rank] == local.len()`, `out.len()` the sum of `counts`). One process:
/// a copy.
pub fn allgather(local: &[f64], counts: &[usize], out: &mut [f64]) -> Result<(), SolveError> {
    init()?;
    let total: usize = counts.iter().sum();
    if out.len() != total || total > c_int::MAX as usize {
        return Err(SolveError::Other(format!(
            "allgather: {} values to gather into {} places (at most {})",
            total,
            out.len(),
            c_int::MAX
        )));
    }
    let counts: Vec<c_int> = counts.iter().map(|&c| c as c_int).collect();
    let mut displs = vec![0 as c_int; counts.len()];
    for r in 1..counts.len() {
        displs[r] = displs[r - 1] + counts[r - 1];
    }
    let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: `local` holds this rank's count of doubles and `out` the sum of all counts,
    // laid out by `displs`; the same counts on every rank.
    let code = unsafe {
        sys::MPI_Allgatherv(
            local.as_ptr().cast(),
            local.len() as c_int,
            sys::dfem_type_double(),
            out.as_mut_ptr().cast(),
            counts.as_ptr(),
            displs.as_ptr(),
            sys::dfem_type_double(),
            comm(),
        )
    };
    mpi_ok(code, "MPI_Allgatherv")
}

/// Overwrites `values` on every rank with rank 0's (`MPI_Bcast` on the communicator of
/// the solves; the same length on every rank).
pub fn broadcast(values: &mut [f64]) -> Result<(), SolveError> {
    init()?;
    if values.len() > c_int::MAX as usize {
        return Err(SolveError::Other(format!(
            "broadcast of {} values exceeds MPI's 32-bit counts",
            values.len()
        )));
    }
    let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: `values.len()` doubles on every rank.
    let code = unsafe {
        sys::MPI_Bcast(
            values.as_mut_ptr().cast(),
            values.len() as c_int,
            sys::dfem_type_double(),
            0,
            comm(),
        )
    };
    mpi_ok(code, "MPI_Bcast")
}

/// An MPI return code as a result.
fn mpi_ok(code: c_int, what: &str) -> Result<(), SolveError> {
    if code == 0 {
        Ok(())
    } else {
        Err(SolveError::Other(format!("{what} failed ({code})")))
    }
}

/// Ends PETSc and MPI if they were started. Every [`Petsc`] must be dropped before.
pub fn finalize() {
    if INIT.get().is_some() {
        let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
        let mut fin: sys::PetscBool = sys::PetscBool_PETSC_FALSE;
        // SAFETY: flag query, then PetscFinalize once, then MPI_Finalize if still needed.
        unsafe {
            sys::PetscFinalized(&mut fin);
            if fin == sys::PetscBool_PETSC_FALSE {
                sys::PetscFinalize();
            }
        }
    }
    // MUMPS in the MPI build may have started MPI without PETSc
    // SAFETY: checks the MPI state before finalizing.
    unsafe { sys::dfem_mpi_finalize() };
}

/// How the unknowns are distributed: `perm[old] = new`, rank r owns new rows
/// `ranges[r]..ranges[r + 1]`.
struct Layout {
    perm: Vec<u32>,
    inv: Vec<u32>,
    ranges: Vec<usize>,
    rank: usize,
}

impl Layout {
    /// Identity on one process; on several, the parts of `given` (one per unknown, each
    /// below `size`) or else METIS k-way parts of the node graph, in rank order. Rank 0's
    /// partition is broadcast, so every rank uses the same even if METIS differed.
    fn new(
        pattern: &CsrPattern,
        rank: usize,
        size: usize,
        given: Option<&[u32]>,
    ) -> Result<Self, SolveError> {
        let n = pattern.n();
        let mut part = match given {
            _ if size <= 1 => vec![0u32; n],
            Some(p) => {
                if p.len() != n || p.iter().any(|&r| r as usize >= size) {
                    return Err(SolveError::Other(format!(
                        "the partition given covers {} unknowns with parts up to {}; \
                         the matrix has {n} unknowns and the run {size} processes",
                        p.len(),
                        p.iter().max().map_or(0, |&r| r)
                    )));
                }
                p.to_vec()
            }
            None => dfem_kernels::metis_partition(pattern, size)?,
        };
        if size > 1 {
            // SAFETY: n integers on every rank (the same pattern everywhere).
            let code = unsafe {
                sys::MPI_Bcast(
                    part.as_mut_ptr().cast(),
                    n as c_int,
                    sys::dfem_type_int(),
                    0,
                    comm(),
                )
            };
            mpi_ok(code, "MPI_Bcast")?;
        }
        let mut counts = vec![0usize; size + 1];
        for &p in &part {
            counts[p as usize + 1] += 1;
        }
        for r in 0..size {
            counts[r + 1] += counts[r];
        }
        let ranges = counts.clone();
        let mut next = counts;
        let mut perm = vec![0u32; n];
        let mut inv = vec![0u32; n];
        for (old, &p) in part.iter().enumerate() {
            let new = next[p as usize];
            next[p as usize] += 1;
            perm[old] = new as u32;
            inv[new] = old as u32;
        }
        Ok(Self {
            perm,
            inv,
            ranges,
            rank,
        })
    }

    fn local(&self) -> std::ops::Range<usize> {
        self.ranges[self.rank]..self.ranges[self.rank + 1]
    }
}

/// The rows of this rank in PETSc's numbering: CSR with global columns, and where each
/// value comes from in dfem's CSR values.
struct LocalRows {
    row_ptr: Vec<sys::PetscInt>,
    cols: Vec<sys::PetscInt>,
    src: Vec<usize>,
    vals: Vec<f64>,
}

impl LocalRows {
    fn new(pattern: &CsrPattern, layout: &Layout) -> Self {
        let mut row_ptr = vec![0 as sys::PetscInt];
        let mut cols = Vec::new();
        let mut src = Vec::new();
        let mut row: Vec<(u32, usize)> = Vec::new();
        for new in layout.local() {
            let old = layout.inv[new] as usize;
            let start = pattern.row_ptr()[old];
            row.clear();
            row.extend(
                pattern
                    .row_cols(old)
                    .iter()
                    .enumerate()
                    .map(|(k, &c)| (layout.perm[c as usize], start + k)),
            );
            row.sort_unstable();
            for &(c, s) in &row {
                cols.push(c as sys::PetscInt);
                src.push(s);
            }
            row_ptr.push(cols.len() as sys::PetscInt);
        }
        let vals = vec![0.0; cols.len()];
        Self {
            row_ptr,
            cols,
            src,
            vals,
        }
    }
}

/// Whether the unknowns come in node pairs (2k, 2k + 1) with identical rows in the pattern
/// (the x and y components of one node of a deformable block), so that the matrix can be
/// given block size 2. Rigid blocks (3 unknowns) or constrained components break it.
fn node_pairs(pattern: &CsrPattern) -> bool {
    let n = pattern.n();
    n.is_multiple_of(2)
        && (0..n / 2).all(|k| pattern.row_cols(2 * k) == pattern.row_cols(2 * k + 1))
}

/// The PETSc backend; see the module documentation.
pub struct Petsc {
    options: String,
    rank: usize,
    size: usize,
    pattern: Option<Arc<CsrPattern>>,
    layout: Option<Layout>,
    rows: Option<LocalRows>,
    mat: sys::Mat,
    ksp: sys::KSP,
    x: sys::PVec,
    b: sys::PVec,
    x_all: sys::PVec,
    gather: sys::VecScatter,
    db: sys::PetscOptions,
    near_null: Vec<Vec<f64>>,
    /// The partition of the unknowns over the ranks given by `set_partition`.
    partition: Option<Vec<u32>>,
    /// dfem's copy of the last factorized matrix (skip test, true residual).
    last: Option<CsrMatrix>,
    ready: bool,
    stats: SolverStats,
}

// SAFETY: the PETSc handles are owned by this value alone and every use goes through the
// process-wide lock; the value moves between threads, it is never shared.
unsafe impl Send for Petsc {}

impl Petsc {
    /// A backend with PETSc options (`-ksp_type cg -pc_type gamg ...`) added to PETSc's
    /// options database before each solver set-up reads it. Starts PETSc if needed.
    pub fn new(options: &str) -> Result<Self, SolveError> {
        let (rank, size) = rank_and_size()?;
        Ok(Self {
            options: options.to_string(),
            rank,
            size,
            pattern: None,
            layout: None,
            rows: None,
            mat: std::ptr::null_mut(),
            ksp: std::ptr::null_mut(),
            x: std::ptr::null_mut(),
            b: std::ptr::null_mut(),
            x_all: std::ptr::null_mut(),
            gather: std::ptr::null_mut(),
            db: std::ptr::null_mut(),
            near_null: Vec::new(),
            partition: None,
            last: None,
            ready: false,
            stats: SolverStats {
                min_pivot_ratio: f64::NAN,
                last_true_residual: f64::NAN,
                ..Default::default()
            },
        })
    }

    /// Number of processes the solves are distributed over.
    pub fn processes(&self) -> usize {
        self.size
    }

    /// The Krylov method and preconditioner PETSc actually uses ("cg+gamg"), after a
    /// `factorize`; empty before.
    pub fn method(&self) -> String {
        if self.ksp.is_null() {
            return String::new();
        }
        let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
        let mut kt: sys::KSPType = std::ptr::null();
        let mut pc: sys::PC = std::ptr::null_mut();
        let mut pt: sys::PCType = std::ptr::null();
        // SAFETY: live KSP; the returned strings are PETSc's, copied at once.
        unsafe {
            sys::KSPGetType(self.ksp, &mut kt);
            sys::KSPGetPC(self.ksp, &mut pc);
            sys::PCGetType(pc, &mut pt);
            let s = |p: *const c_char| {
                if p.is_null() {
                    "?".to_string()
                } else {
                    CStr::from_ptr(p).to_string_lossy().into_owned()
                }
            };
            format!("{}+{}", s(kt), s(pt))
        }
    }

    fn destroy(&mut self) {
        // SAFETY: each handle is destroyed once (PETSc nulls it) and only if PETSc runs.
        unsafe {
            let mut fin: sys::PetscBool = sys::PetscBool_PETSC_FALSE;
            sys::PetscFinalized(&mut fin);
            if fin == sys::PetscBool_PETSC_TRUE {
                return;
            }
            if !self.ksp.is_null() {
                sys::KSPDestroy(&mut self.ksp);
            }
            if !self.gather.is_null() {
                sys::VecScatterDestroy(&mut self.gather);
            }
            for v in [&mut self.x, &mut self.b, &mut self.x_all] {
                if !v.is_null() {
                    sys::VecDestroy(v);
                }
            }
            if !self.mat.is_null() {
                sys::MatDestroy(&mut self.mat);
            }
            if !self.db.is_null() {
                sys::PetscOptionsDestroy(&mut self.db);
            }
        }
        self.ready = false;
    }

    /// Creates the matrix (pattern, zero values), vectors, gather context and KSP.
    fn create(&mut self, pattern: &CsrPattern) -> Result<(), SolveError> {
        let layout = Layout::new(pattern, self.rank, self.size, self.partition.as_deref())?;
        let mut rows = LocalRows::new(pattern, &layout);
        let nloc = layout.local().len() as sys::PetscInt;
        let n = pattern.n() as sys::PetscInt;
        let c = comm();
        call!(MatCreate(c, &mut self.mat))?;
        call!(MatSetSizes(self.mat, nloc, nloc, n, n))?;
        call!(MatSetType(self.mat, c"aij".as_ptr()))?;
        if node_pairs(pattern) {
            // 2 unknowns per node: GAMG aggregates whole nodes (block size 2)
            call!(MatSetBlockSize(self.mat, 2))?;
        }
        // the CSR preallocation of the type that applies; the other call is a no-op
        call!(MatSeqAIJSetPreallocationCSR(
            self.mat,
            rows.row_ptr.as_ptr(),
            rows.cols.as_ptr(),
            rows.vals.as_ptr()
        ))?;
        call!(MatMPIAIJSetPreallocationCSR(
            self.mat,
            rows.row_ptr.as_ptr(),
            rows.cols.as_ptr(),
            rows.vals.as_ptr()
        ))?;
        call!(MatSetOption(
            self.mat,
            sys::MatOption_MAT_SPD,
            sys::PetscBool_PETSC_TRUE
        ))?;
        call!(MatCreateVecs(self.mat, &mut self.x, &mut self.b))?;
        call!(VecScatterCreateToAll(
            self.x,
            &mut self.gather,
            &mut self.x_all
        ))?;
        call!(KSPCreate(c, &mut self.ksp))?;
        call!(PetscOptionsCreate(&mut self.db))?;
        let env = std::env::var("PETSC_OPTIONS").unwrap_or_default();
        for opts in [env.as_str(), self.options.as_str()] {
            if !opts.trim().is_empty() {
                let opts = CString::new(opts).map_err(|_| {
                    SolveError::Other("PETSc options contain a NUL character".into())
                })?;
                call!(PetscOptionsInsertString(self.db, opts.as_ptr()))?;
            }
        }
        call!(PetscObjectSetOptions(self.ksp.cast(), self.db))?;
        call!(KSPSetOperators(self.ksp, self.mat, self.mat))?;
        call!(KSPSetType(self.ksp, c"cg".as_ptr()))?;
        let mut pc: sys::PC = std::ptr::null_mut();
        call!(KSPGetPC(self.ksp, &mut pc))?;
        call!(PCSetType(pc, c"gamg".as_ptr()))?;
        call!(KSPSetTolerances(
            self.ksp,
            DEFAULT_RTOL,
            -2.0, // PETSC_DEFAULT
            -2.0,
            DEFAULT_MAX_IT
        ))?;
        call!(KSPSetNormType(
            self.ksp,
            sys::KSPNormType_KSP_NORM_UNPRECONDITIONED
        ))?;
        call!(KSPSetFromOptions(self.ksp))?;
        rows.vals.fill(0.0);
        self.layout = Some(layout);
        self.rows = Some(rows);
        self.attach_near_null_space()?;
        Ok(())
    }

    /// Hands the stored near-null space (dfem numbering, full length on every rank) to the
    /// matrix: each vector restricted to this rank's rows, orthonormalized (Gram–Schmidt
    /// with PETSc's parallel dot products, as MatNullSpaceCreate requires).
    fn attach_near_null_space(&mut self) -> Result<(), SolveError> {
        if self.mat.is_null() || self.near_null.is_empty() {
            return Ok(());
        }
        let layout = self.layout.as_ref().expect("layout with the matrix");
        let mut vecs: Vec<sys::PVec> = Vec::new();
        for mode in &self.near_null {
            let mut v: sys::PVec = std::ptr::null_mut();
            call!(VecDuplicate(self.x, &mut v))?;
            let mut arr: *mut f64 = std::ptr::null_mut();
            call!(VecGetArray(v, &mut arr))?;
            let range = layout.local();
            // SAFETY: the local part of v has range.len() entries.
            let local = unsafe { std::slice::from_raw_parts_mut(arr, range.len()) };
            for (k, new) in range.enumerate() {
                local[k] = mode[layout.inv[new] as usize];
            }
            call!(VecRestoreArray(v, &mut arr))?;
            for &u in &vecs {
                let mut d = 0.0;
                call!(VecDot(v, u, &mut d))?;
                call!(VecAXPY(v, -d, u))?;
            }
            let mut norm = 0.0;
            call!(VecNormalize(v, &mut norm))?;
            if norm > 0.0 {
                vecs.push(v);
            } else {
                call!(VecDestroy(&mut v))?;
            }
        }
        let mut nsp: sys::MatNullSpace = std::ptr::null_mut();
        call!(MatNullSpaceCreate(
            comm(),
            sys::PetscBool_PETSC_FALSE,
            vecs.len() as sys::PetscInt,
            vecs.as_ptr(),
            &mut nsp
        ))?;
        call!(MatSetNearNullSpace(self.mat, nsp))?;
        call!(MatNullSpaceDestroy(&mut nsp))?;
        for v in &mut vecs {
            call!(VecDestroy(v))?;
        }
        Ok(())
    }

    /// Resident memory of the process, bytes (PETSc's measure).
    fn resident() -> f64 {
        let mut m: sys::PetscLogDouble = 0.0;
        // SAFETY: output double.
        unsafe { sys::PetscMemoryGetCurrentUsage(&mut m) };
        m
    }
}

impl Drop for Petsc {
    fn drop(&mut self) {
        let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
        self.destroy();
    }
}

impl LinearBackend for Petsc {
    fn name(&self) -> &'static str {
        "petsc"
    }

    fn analyze(&mut self, pattern: &Arc<CsrPattern>) -> Result<(), SolveError> {
        if self
            .pattern
            .as_ref()
            .is_some_and(|p| p.id() == pattern.id())
        {
            return Ok(());
        }
        let t0 = Instant::now();
        let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
        self.destroy();
        self.pattern = None;
        self.last = None;
        if pattern.n() > sys::PetscInt::MAX as usize || pattern.nnz() > sys::PetscInt::MAX as usize
        {
            return Err(SolveError::Other(format!(
                "PETSc: {} unknowns or {} entries exceed its 32-bit indices (PetscInt)",
                pattern.n(),
                pattern.nnz()
            )));
        }
        let r = self.create(pattern);
        if r.is_err() {
            self.destroy();
        }
        r?;
        self.pattern = Some(pattern.clone());
        self.stats.symbolic_factorizations += 1;
        self.stats.symbolic_seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }

    fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        self.analyze(&a.pattern)?;
        if self.ready
            && self
                .last
                .as_ref()
                .is_some_and(|l| same_bits(&l.values, &a.values))
        {
            self.stats.skipped_factorizations += 1;
            return Ok(());
        }
        let t0 = Instant::now();
        let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
        self.ready = false;
        let layout = self.layout.as_ref().expect("analyzed");
        let rows = self.rows.as_mut().expect("analyzed");
        for (v, &s) in rows.vals.iter_mut().zip(&rows.src) {
            *v = a.values[s];
        }
        for (k, new) in layout.local().enumerate() {
            let (s, e) = (rows.row_ptr[k] as usize, rows.row_ptr[k + 1] as usize);
            let row = new as sys::PetscInt;
            call!(MatSetValues(
                self.mat,
                1,
                &row,
                (e - s) as sys::PetscInt,
                rows.cols[s..e].as_ptr(),
                rows.vals[s..e].as_ptr(),
                sys::InsertMode_INSERT_VALUES
            ))?;
        }
        call!(MatAssemblyBegin(
            self.mat,
            sys::MatAssemblyType_MAT_FINAL_ASSEMBLY
        ))?;
        call!(MatAssemblyEnd(
            self.mat,
            sys::MatAssemblyType_MAT_FINAL_ASSEMBLY
        ))?;
        let before = Self::resident();
        call!(KSPSetOperators(self.ksp, self.mat, self.mat))?;
        call!(KSPSetUp(self.ksp))?;
        self.stats.memory_bytes = (Self::resident() - before).max(0.0) as usize;
        self.stats.numeric_factorizations += 1;
        self.stats.numeric_seconds += t0.elapsed().as_secs_f64();
        self.last = Some(a.clone());
        self.ready = true;
        Ok(())
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        if !self.ready {
            return Err(SolveError::Other(
                "PETSc: solve before a successful factorize".into(),
            ));
        }
        let a = self.last.as_ref().expect("factorized");
        let n = a.pattern.n();
        if rhs.len() != n {
            return Err(SolveError::Other(format!(
                "PETSc: right-hand side of length {}, the matrix has {n} rows",
                rhs.len()
            )));
        }
        let t0 = Instant::now();
        let b_norm = rhs.iter().map(|v| v * v).sum::<f64>().sqrt();
        if b_norm == 0.0 {
            rhs.fill(0.0);
            self.stats.solves += 1;
            self.stats.last_iterations = 0;
            self.stats.last_true_residual = 0.0;
            return Ok(());
        }
        let b_in = rhs.to_vec();
        let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
        let layout = self.layout.as_ref().expect("analyzed");
        let range = layout.local();
        let mut arr: *mut f64 = std::ptr::null_mut();
        call!(VecGetArray(self.b, &mut arr))?;
        {
            // SAFETY: the local part of b has range.len() entries.
            let local = unsafe { std::slice::from_raw_parts_mut(arr, range.len()) };
            for (k, new) in range.clone().enumerate() {
                local[k] = rhs[layout.inv[new] as usize];
            }
        }
        call!(VecRestoreArray(self.b, &mut arr))?;
        call!(KSPSolve(self.ksp, self.b, self.x))?;
        let mut its: sys::PetscInt = 0;
        call!(KSPGetIterationNumber(self.ksp, &mut its))?;
        let mut reason: sys::KSPConvergedReason = 0;
        call!(KSPGetConvergedReason(self.ksp, &mut reason))?;
        call!(VecScatterBegin(
            self.gather,
            self.x,
            self.x_all,
            sys::InsertMode_INSERT_VALUES,
            sys::ScatterMode_SCATTER_FORWARD
        ))?;
        call!(VecScatterEnd(
            self.gather,
            self.x,
            self.x_all,
            sys::InsertMode_INSERT_VALUES,
            sys::ScatterMode_SCATTER_FORWARD
        ))?;
        call!(VecGetArray(self.x_all, &mut arr))?;
        {
            // SAFETY: x_all is a sequential vector of all n entries.
            let all = unsafe { std::slice::from_raw_parts(arr, n) };
            for (old, v) in rhs.iter_mut().enumerate() {
                *v = all[layout.perm[old] as usize];
            }
        }
        call!(VecRestoreArray(self.x_all, &mut arr))?;
        drop(_guard);
        let its = its.max(0) as usize;
        self.stats.solves += 1;
        self.stats.iterations += its;
        self.stats.last_iterations = its;
        let mut ax = vec![0.0; n];
        a.mul_vec(rhs, &mut ax);
        let res = ax
            .iter()
            .zip(&b_in)
            .map(|(p, q)| (p - q) * (p - q))
            .sum::<f64>()
            .sqrt()
            / b_norm;
        self.stats.last_true_residual = res;
        self.stats.solve_seconds += t0.elapsed().as_secs_f64();
        if reason < 0 || !res.is_finite() {
            return Err(SolveError::NoConvergence {
                iterations: its,
                residual: res,
            });
        }
        Ok(())
    }

    fn stats(&self) -> &SolverStats {
        &self.stats
    }

    fn partition_parts(&self) -> Option<usize> {
        (self.size > 1).then_some(self.size)
    }

    fn set_partition(&mut self, part: &[u32]) -> Result<(), SolveError> {
        if self.size > 1 && self.partition.as_deref() != Some(part) {
            self.partition = Some(part.to_vec());
            // the layout follows the partition: analyze again at the next factorization
            let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
            self.destroy();
            self.pattern = None;
            self.last = None;
            self.ready = false;
        }
        Ok(())
    }

    fn set_near_null_space(&mut self, modes: &[Vec<f64>]) -> Result<(), SolveError> {
        self.near_null = modes.to_vec();
        if !self.mat.is_null() {
            let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
            self.attach_near_null_space()?;
            // the preconditioner must be rebuilt with the new space
            self.ready = false;
            self.last = None;
        }
        Ok(())
    }
}
