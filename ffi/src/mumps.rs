//! MUMPS (multifrontal direct solver) as a [`LinearBackend`]: symbolic analysis (JOB = 1)
//! once per pattern, numeric factorization (JOB = 2) when the values change, solves
//! (JOB = 3) with the centralized right-hand side. Three factorizations ([`Symmetry`]):
//! `SYM = 2` (symmetric LDLᵀ with threshold pivoting; the default, `mumps`), `SYM = 1`
//! (LDLᵀ without pivoting for positive definite matrices, `mumps-spd`), both given the upper
//! triangle only, and `SYM = 0` (LU, the whole matrix, `mumps-lu`). Indices are 1-based.
//!
//! Singularity: MUMPS' null-pivot detection (ICNTL(24) = 1) flags a pivot whose row in the
//! scaled matrix has infinity norm below CNTL(3) = [`NULL_PIVOT_THRESHOLD`] × ‖A‖; then
//! `stats().min_pivot_ratio` is 0 at the first such unknown (the caller's mechanism test,
//! the same one faer's pivot ratio feeds), otherwise NaN (MUMPS does not report pivots).
//! MUMPS 5.5 does not run that detection with `SYM = 1` (measured: a pivot 1e-15 × the
//! diagonal passes unflagged), which is why dfem's default MUMPS backend is `SYM = 2`: on
//! a positive definite matrix it pivots on the diagonal like `SYM = 1`, and it reports
//! both null pivots and the inertia (INFOG(12) negative pivots: not positive definite).
//!
//! One process: the sequential library (`libdmumps_seq`) or, when PETSc is compiled in, the
//! MPI library on MPI_COMM_SELF. Calls into MUMPS are serialized by a process-wide lock
//! (its Fortran run time is not re-entrant across instances on different threads).
//!
//! Distributed (feature `mpi`, under `mpirun` with N > 1 processes): one MUMPS instance
//! on MPI_COMM_WORLD (PAR = 1, the host works too), with MUMPS' distributed assembled
//! input (ICNTL(18) = 3): each process gives only the entries of its own rows
//! (IRN_loc, JCN_loc, A_loc; for the symmetric factorizations the entries on or above the
//! diagonal of its rows, so each entry of the upper triangle comes from one process), its
//! rows being the unknowns of its part of the partition given with
//! [`LinearBackend::set_partition`] (dfem's block partition, the same as the assembly's and
//! PETSc's), or else N contiguous ranges. The analysis (ordering) runs on the host
//! (ICNTL(28) = 1), factorization and solve on all processes; the right-hand side is
//! centralized on the host (rank 0's copy is used) and the solution, centralized on the
//! host (ICNTL(21) = 0), is broadcast to every process, as PETSc's backend returns it.

use crate::mumps_sys::{self, DmumpsStrucC};
use dfem_kernels::{same_bits, CsrMatrix, CsrPattern, LinearBackend, SolveError, SolverStats};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Instant;

/// Relative threshold of MUMPS' null-pivot detection, CNTL(3): a pivot row whose norm is
/// below this fraction of ‖A‖ (after MUMPS' scaling) counts as null. The same order as the
/// pivot ratio below which dfem declares a stiffness matrix singular (a mechanism gives
/// ~1e-16, sound structures above ~1e-9).
pub const NULL_PIVOT_THRESHOLD: f64 = 1e-12;

/// Times the working space is enlarged (ICNTL(14) doubled) when MUMPS reports it too small.
const WORKSPACE_RETRIES: usize = 4;

static LOCK: Mutex<()> = Mutex::new(());

/// MUMPS' COMM_FORTRAN, fetched once (it may start MPI).
static COMM: OnceLock<i32> = OnceLock::new();

/// Which factorization MUMPS computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Symmetry {
    /// SYM = 2: symmetric, LDLᵀ with threshold pivoting, null-pivot detection; a negative
    /// pivot is an error (dfem's stiffness matrices must be positive definite).
    Symmetric,
    /// SYM = 1: symmetric positive definite, LDLᵀ without pivoting; no null-pivot detection.
    PositiveDefinite,
    /// SYM = 0: general, LU with threshold partial pivoting.
    General,
}

/// The MUMPS backend; see the module documentation.
pub struct Mumps {
    symmetry: Symmetry,
    inst: Box<DmumpsStrucC>,
    initialized: bool,
    pattern: Option<Arc<CsrPattern>>,
    /// 1-based coordinates of the entries passed to MUMPS, and where each comes from in
    /// the CSR values.
    irn: Vec<i32>,
    jcn: Vec<i32>,
    src: Vec<usize>,
    a: Vec<f64>,
    /// Values of the last successful factorization (for the skip test).
    last: Option<Vec<f64>>,
    factorized: bool,
    stats: SolverStats,
    /// This process's rank and the number of processes of a distributed instance
    /// (`(0, 1)`: one process, centralized input).
    rank: usize,
    size: usize,
    /// The partition of the unknowns over the processes given by `set_partition`.
    partition: Option<Vec<u32>>,
}

/// Rank and number of processes of a distributed MUMPS: those of `mpirun` with feature
/// `mpi` (MPI started with PETSc), else `(0, 1)`.
fn rank_and_size() -> Result<(usize, usize), SolveError> {
    #[cfg(all(mumps_mpi, feature = "mpi"))]
    {
        crate::petsc::rank_and_size()
    }
    #[cfg(not(all(mumps_mpi, feature = "mpi")))]
    {
        Ok((0, 1))
    }
}

/// Overwrites `values` with rank 0's on every process (distributed instances only).
fn broadcast(values: &mut [f64]) -> Result<(), SolveError> {
    #[cfg(all(mumps_mpi, feature = "mpi"))]
    {
        crate::petsc::broadcast(values)
    }
    #[cfg(not(all(mumps_mpi, feature = "mpi")))]
    {
        let _ = values;
        Ok(())
    }
}

// SAFETY: the raw pointers inside the MUMPS structure point into this value's own vectors
// (or MUMPS' own allocations); the value is moved between threads, never shared.
unsafe impl Send for Mumps {}

impl Mumps {
    /// A new instance (MUMPS' JOB = -1 runs at once; errors if the installed header does not
    /// match this binding).
    pub fn new(symmetry: Symmetry) -> Result<Self, SolveError> {
        mumps_sys::check_layout().map_err(SolveError::Other)?;
        let (rank, size) = rank_and_size()?;
        // SAFETY: DmumpsStrucC is plain data (integers, floats, null pointers, chars).
        let inst: Box<DmumpsStrucC> = Box::new(unsafe { std::mem::zeroed() });
        let mut m = Self {
            symmetry,
            inst,
            initialized: false,
            pattern: None,
            irn: Vec::new(),
            jcn: Vec::new(),
            src: Vec::new(),
            a: Vec::new(),
            last: None,
            factorized: false,
            stats: SolverStats {
                min_pivot_ratio: f64::NAN,
                last_true_residual: f64::NAN,
                ..Default::default()
            },
            rank,
            size,
            partition: None,
        };
        m.inst.sym = match symmetry {
            Symmetry::Symmetric => 2,
            Symmetry::PositiveDefinite => 1,
            Symmetry::General => 0,
        };
        m.inst.par = 1;
        m.inst.comm_fortran = *COMM.get_or_init(|| {
            // in the MPI build, MPI starts with PETSc (once per process, see petsc::init)
            #[cfg(mumps_mpi)]
            let _ = crate::petsc::rank_and_size();
            // SAFETY: sets OpenBLAS's thread count; returns an integer (initializes MPI if
            // PETSc could not).
            unsafe {
                mumps_sys::dfem_blas_single_thread();
                mumps_sys::dfem_mumps_comm()
            }
        });
        if size > 1 {
            // SAFETY: returns an integer handle (MPI was started by rank_and_size).
            m.inst.comm_fortran = unsafe { mumps_sys::dfem_mumps_comm_world() };
        }
        m.call(-1)?;
        m.initialized = true;
        // ICNTL(1..4): no output; ICNTL(24): null pivot detection, CNTL(3) its threshold.
        m.inst.icntl[0] = -1;
        m.inst.icntl[1] = -1;
        m.inst.icntl[2] = -1;
        m.inst.icntl[3] = 0;
        m.inst.icntl[23] = 1;
        m.inst.cntl[2] = NULL_PIVOT_THRESHOLD;
        if size > 1 {
            // ICNTL(18) = 3: distributed assembled input; ICNTL(28) = 1: sequential analysis
            m.inst.icntl[17] = 3;
            m.inst.icntl[27] = 1;
        }
        Ok(m)
    }

    /// Number of processes the instance works on (1 unless distributed).
    pub fn processes(&self) -> usize {
        self.size
    }

    /// Whether this process gives row `i` of a matrix of `n` rows: all of them on one
    /// process; else those of its part of the given partition, or its contiguous range.
    fn owns(&self, i: usize, n: usize) -> bool {
        if self.size <= 1 {
            return true;
        }
        match &self.partition {
            Some(p) if p.len() == n => p[i] as usize == self.rank,
            _ => i * self.size / n.max(1) == self.rank,
        }
    }

    /// Runs one MUMPS job and turns INFOG(1) < 0 into an error with its meaning.
    fn call(&mut self, job: i32) -> Result<(), SolveError> {
        self.inst.job = job;
        {
            let _guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
            // SAFETY: the structure was initialized by JOB = -1 (or is being), and every
            // pointer set in it refers to live vectors of self with the sizes given.
            unsafe { mumps_sys::dmumps_c(&mut *self.inst) };
        }
        let (i1, i2) = (self.inst.infog[0], self.inst.infog[1]);
        if i1 < 0 {
            return Err(self.error(job, i1, i2));
        }
        Ok(())
    }

    fn error(&self, job: i32, i1: i32, i2: i32) -> SolveError {
        let phase = match job {
            -1 => "initialization",
            1 => "analysis",
            2 => "factorization",
            3 => "solve",
            _ => "call",
        };
        let what = match i1 {
            -5 | -7 | -13 => format!("could not allocate memory ({i2} items asked for)"),
            -6 => format!("the matrix is structurally singular (structural rank {i2})"),
            -8 | -9 | -14 | -15 | -17 | -20 => {
                "working space too small even after enlarging it (ICNTL(14))".to_string()
            }
            -10 => {
                let what = if self.symmetry != Symmetry::General {
                    "numerically singular or not positive definite"
                } else {
                    "numerically singular"
                };
                format!("the matrix is {what} (INFO(1) = -10, {i2} eliminated pivots)")
            }
            -16 => format!("N out of range (N = {i2})"),
            -22 => format!("a pointer array is wrong or missing (INFO(2) = {i2})"),
            _ => format!("INFO(1) = {i1}, INFO(2) = {i2} (see the MUMPS user guide, section 8)"),
        };
        SolveError::Other(format!("MUMPS {phase}: {what}"))
    }

    /// Runs `job`, enlarging the working space and retrying when MUMPS asks for it.
    fn call_with_retries(&mut self, job: i32) -> Result<(), SolveError> {
        for _ in 0..WORKSPACE_RETRIES {
            match self.call(job) {
                Err(_) if matches!(self.inst.infog[0], -8 | -9 | -14 | -15 | -17 | -20) => {
                    self.inst.icntl[13] = (self.inst.icntl[13].max(20)) * 2;
                }
                r => return r,
            }
        }
        self.call(job)
    }
}

impl Drop for Mumps {
    fn drop(&mut self) {
        if self.initialized {
            let _ = self.call(-2);
        }
    }
}

/// INFOG entries that count in millions when negative (INFOG(29), the factor entries).
fn mumps_count(v: i32) -> usize {
    if v < 0 {
        (-(v as i64) * 1_000_000) as usize
    } else {
        v as usize
    }
}

impl LinearBackend for Mumps {
    fn name(&self) -> &'static str {
        match self.symmetry {
            Symmetry::Symmetric => "mumps",
            Symmetry::PositiveDefinite => "mumps-spd",
            Symmetry::General => "mumps-lu",
        }
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
        let n = pattern.n();
        if n > i32::MAX as usize || pattern.nnz() > i32::MAX as usize {
            return Err(SolveError::Other(format!(
                "MUMPS: {n} unknowns or {} entries exceed its 32-bit indices",
                pattern.nnz()
            )));
        }
        self.irn.clear();
        self.jcn.clear();
        self.src.clear();
        let upper_only = self.symmetry != Symmetry::General;
        let owned: Vec<bool> = (0..n).map(|i| self.owns(i, n)).collect();
        for i in (0..n).filter(|&i| owned[i]) {
            let start = pattern.row_ptr()[i];
            for (k, &j) in pattern.row_cols(i).iter().enumerate() {
                if upper_only && (j as usize) < i {
                    continue;
                }
                self.irn.push(i as i32 + 1);
                self.jcn.push(j as i32 + 1);
                self.src.push(start + k);
            }
        }
        self.a = vec![0.0; self.src.len()];
        self.inst.n = n as i32;
        self.inst.nz = 0;
        if self.size > 1 {
            self.inst.nnz_loc = self.irn.len() as i64;
            self.inst.nz_loc = 0;
            self.inst.irn_loc = self.irn.as_mut_ptr();
            self.inst.jcn_loc = self.jcn.as_mut_ptr();
            self.inst.a_loc = self.a.as_mut_ptr();
        } else {
            self.inst.nnz = self.irn.len() as i64;
            self.inst.irn = self.irn.as_mut_ptr();
            self.inst.jcn = self.jcn.as_mut_ptr();
            self.inst.a = self.a.as_mut_ptr();
        }
        self.pattern = None;
        self.factorized = false;
        self.last = None;
        self.call_with_retries(1)?;
        self.pattern = Some(pattern.clone());
        self.stats.symbolic_factorizations += 1;
        self.stats.symbolic_seconds += t0.elapsed().as_secs_f64();
        Ok(())
    }

    fn factorize(&mut self, a: &CsrMatrix) -> Result<(), SolveError> {
        self.analyze(&a.pattern)?;
        if self.factorized
            && self
                .last
                .as_deref()
                .is_some_and(|v| same_bits(v, &a.values))
        {
            self.stats.skipped_factorizations += 1;
            return Ok(());
        }
        let t0 = Instant::now();
        self.factorized = false;
        for (dst, &s) in self.a.iter_mut().zip(&self.src) {
            *dst = a.values[s];
        }
        if self.size > 1 {
            self.inst.a_loc = self.a.as_mut_ptr();
        } else {
            self.inst.a = self.a.as_mut_ptr();
        }
        self.call_with_retries(2)?;
        self.stats.numeric_factorizations += 1;
        self.stats.numeric_seconds += t0.elapsed().as_secs_f64();
        self.stats.factor_nnz = mumps_count(self.inst.infog[28]);
        // INFOG(22): megabytes actually used by the factorization (all processes)
        self.stats.memory_bytes = self.inst.infog[21].max(0) as usize * 1_000_000;
        let nulls = self.inst.infog[27];
        if nulls > 0 {
            // SAFETY: MUMPS allocated PIVNUL_LIST with INFOG(28) entries (1-based rows), on
            // the host (INFOG is global: every process comes here together)
            let first = if self.rank == 0 && !self.inst.pivnul_list.is_null() {
                unsafe { *self.inst.pivnul_list }
            } else {
                1
            };
            let mut first = [f64::from(first)];
            if self.size > 1 {
                broadcast(&mut first)?;
            }
            self.stats.min_pivot_ratio = 0.0;
            self.stats.min_pivot_index = (first[0] as i64 - 1).max(0) as usize;
        } else {
            self.stats.min_pivot_ratio = f64::NAN;
            self.stats.min_pivot_index = 0;
        }
        if self.symmetry != Symmetry::General && self.inst.infog[11] > 0 {
            // INFOG(12): negative pivots (the inertia with SYM = 2)
            return Err(SolveError::Other(format!(
                "MUMPS factorization: the matrix is not positive definite ({} negative pivots)",
                self.inst.infog[11]
            )));
        }
        self.factorized = true;
        self.last = Some(a.values.clone());
        Ok(())
    }

    fn solve(&mut self, rhs: &mut [f64]) -> Result<(), SolveError> {
        if !self.factorized {
            return Err(SolveError::Other(
                "MUMPS: solve before a successful factorization".into(),
            ));
        }
        let n = self.inst.n as usize;
        if rhs.len() != n {
            return Err(SolveError::Other(format!(
                "MUMPS: right-hand side of length {}, the matrix has {n} rows",
                rhs.len()
            )));
        }
        let t0 = Instant::now();
        self.inst.rhs = rhs.as_mut_ptr();
        self.inst.nrhs = 1;
        self.inst.lrhs = n as i32;
        self.inst.icntl[19] = 0; // ICNTL(20): dense right-hand side
        self.inst.icntl[20] = 0; // ICNTL(21): centralized solution (in rhs, on the host)
        if self.rank != 0 {
            // the right-hand side and the solution live on the host only
            self.inst.rhs = std::ptr::null_mut();
        }
        let r = self.call(3);
        self.inst.rhs = std::ptr::null_mut();
        r?;
        if self.size > 1 {
            broadcast(rhs)?;
        }
        self.stats.solves += 1;
        self.stats.solve_seconds += t0.elapsed().as_secs_f64();
        if rhs.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::Singular {
                index: rhs.iter().position(|v| !v.is_finite()).unwrap_or(0),
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
            if part.iter().any(|&p| p as usize >= self.size) {
                return Err(SolveError::Other(format!(
                    "MUMPS: a partition into parts up to {} for {} processes",
                    part.iter().max().map_or(0, |&p| p),
                    self.size
                )));
            }
            self.partition = Some(part.to_vec());
            // the local entries follow the partition: analyze again at the next factorization
            self.pattern = None;
            self.factorized = false;
            self.last = None;
        }
        Ok(())
    }
}
