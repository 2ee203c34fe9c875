//! Linear backend selection (the PETSc pattern: chosen at run time by name, a backend not
//! compiled in is an error, not a crash).

pub use dfem_kernels::{LinearBackend, SolveError, BACKENDS};

/// The options of a backend beyond its name (`dfem run` / `dfem bench-solvers`).
#[derive(Debug, Clone, Default)]
pub struct BackendOptions {
    /// Options for PETSc's database when the backend is `petsc` (`--petsc-options`).
    pub petsc_options: String,
    /// Number of subdomains of `faer-substructured` (`--subdomains K`, K ≥ 1; default 2).
    /// Refused with any other backend.
    pub subdomains: Option<usize>,
}

/// The backend that takes `--subdomains`.
pub(crate) const SUBSTRUCTURED: &str = "faer-substructured";

/// Default backend: faer's supernodal Cholesky (LLᵀ) with the symbolic phase cached and
/// the blocks' interiors condensed out where that pays (`faer-condensed`: from the second
/// factorization on, when the condensed matrix costs at most half the whole one; else,
/// and always for rigid blocks, bit for bit `faer-cholesky`).
pub const DEFAULT: &str = "faer-condensed";

/// Every backend name `--solver` knows: the built-in ones ([`BACKENDS`]) and those of
/// `dfem-ffi` (MUMPS, PETSc), whether compiled in or not.
pub fn all_names() -> Vec<&'static str> {
    BACKENDS
        .iter()
        .copied()
        .chain(dfem_ffi::ALL.iter().map(|(n, _)| *n))
        .collect()
}

/// The backends compiled into this build (what `dfem bench-solvers` runs).
pub fn available_names() -> Vec<&'static str> {
    BACKENDS.iter().chain(dfem_ffi::BACKENDS).copied().collect()
}

/// Refuses a number of subdomains (`--subdomains K`) below 1.
pub fn check_subdomains(k: usize) -> crate::Result<()> {
    if k == 0 {
        return Err(crate::Error::new("--subdomains must be at least 1 (got 0)")
            .place("option --subdomains")
            .fix("give a positive number of subdomains, e.g. --subdomains 2 (one per core)"));
    }
    Ok(())
}

/// Build a backend from its name (`--solver`) with default options.
pub fn backend(name: &str) -> crate::Result<Box<dyn LinearBackend>> {
    backend_with(name, &BackendOptions::default())
}

/// Build a backend from its name (`--solver`) and options (`--petsc-options`).
pub fn backend_with(name: &str, opts: &BackendOptions) -> crate::Result<Box<dyn LinearBackend>> {
    if let Some(k) = opts.subdomains {
        if name != SUBSTRUCTURED {
            return Err(crate::Error::new(format!(
                "--subdomains applies to --solver {SUBSTRUCTURED} only, not to '{name}'"
            ))
            .place("option --subdomains")
            .fix(format!(
                "add `--solver {SUBSTRUCTURED}` or drop --subdomains"
            )));
        }
        check_subdomains(k)?;
        return Ok(Box::new(
            dfem_kernels::FaerCholeskySubstructured::new().with_subdomains(k),
        ));
    }
    let ffi = dfem_ffi::FfiOptions {
        petsc_options: opts.petsc_options.clone(),
    };
    if let Some(built) = dfem_ffi::backend_from_name(name, &ffi) {
        return built.map_err(|e| {
            let feature = dfem_ffi::ALL
                .iter()
                .find(|(n, _)| *n == name)
                .map_or("", |(_, f)| *f);
            crate::Error::new(e).place("option --solver").fix(format!(
                "build dfem with `--features {feature}` on a machine with the libraries \
                 installed, or use one of: {}",
                available_names().join(", ")
            ))
        });
    }
    dfem_kernels::backend_from_name(name).map_err(|_| {
        crate::Error::new(format!("unknown linear backend '{name}'"))
            .place("option --solver")
            .fix(format!(
                "use one of: {} (available in this build: {})",
                all_names().join(", "),
                available_names().join(", ")
            ))
    })
}

/// The backend of the nonsymmetric tangent corrections (Newton steps, arc-length
/// increments; the friction couples a slipping contact's shear to its normal force) in a
/// run whose `--solver` is `main`: the LU of the same family, MUMPS' unsymmetric
/// factorization for the MUMPS backends in a serial run, faer's sparse LU for every
/// other (faer's, PCG, PETSc, whose default Krylov options are for symmetric matrices,
/// and any backend under `mpirun`).
pub fn tangent_backend(main: &str) -> crate::Result<Box<dyn LinearBackend>> {
    let serial = dfem_ffi::process_rank().1 <= 1;
    let name = if serial && main.starts_with("mumps") {
        "mumps-lu"
    } else {
        "faer-lu"
    };
    backend(name)
}

/// The rigid-body modes of the blocks, as the near-null space of the stiffness matrix
/// ([`LinearBackend::set_near_null_space`]): three vectors of length `mesh.n_dofs`, the
/// translation in x, the translation in y and the in-plane rotation, each block moving
/// rigidly about its own centroid (docs/theory.md §2: a block's elastic energy vanishes on these
/// motions; only the contact springs of §3 resist them). On a deformable block's node at
/// (x, y) the rotation is (−(y − y_c), x − x_c); a rigid block's unknowns (u, v, θ) get
/// (1, 0, 0), (0, 1, 0), (0, 0, 1). Lengths in m; fixed blocks have no unknowns.
pub fn rigid_body_modes(mesh: &crate::mesh::Mesh) -> Vec<Vec<f64>> {
    use crate::mesh::BlockDofs;
    let n = mesh.n_dofs;
    let mut modes = vec![vec![0.0; n]; 3];
    for b in &mesh.blocks {
        match b.dofs {
            BlockDofs::Fixed => {}
            BlockDofs::Rigid { first, .. } => {
                for (k, mode) in modes.iter_mut().enumerate() {
                    mode[first as usize + k] = 1.0;
                }
            }
            BlockDofs::Deformable => {
                let c = b.centroid;
                for node in b.nodes.clone() {
                    let d = mesh.node_dofs[node as usize];
                    let p = mesh.nodes[node as usize];
                    let rot = [-(p[1] - c[1]), p[0] - c[0]];
                    for comp in 0..2 {
                        let k = d[comp];
                        if k == dfem_kernels::CONSTRAINED {
                            continue;
                        }
                        modes[comp][k as usize] = 1.0;
                        modes[2][k as usize] = rot[comp];
                    }
                }
            }
        }
    }
    modes
}

/// The blocks' interiors, for [`LinearBackend::set_interiors`]: the index of its block
/// (in `mesh.blocks`) for every free unknown of a deformable block's node that no contact
/// acts on (neither of its two points nor the edge that carries its normal), `u32::MAX`
/// for every other unknown (contact nodes, rigid blocks).
pub fn interior_groups(mesh: &crate::mesh::Mesh) -> Vec<u32> {
    use crate::mesh::BlockDofs;
    let mut on_contact = vec![false; mesh.nodes.len()];
    for c in &mesh.contacts {
        for n in [c.node_l, c.node_m, c.edge_l[0], c.edge_l[1]] {
            on_contact[n as usize] = true;
        }
    }
    let mut group = vec![u32::MAX; mesh.n_dofs];
    for (b, blk) in mesh.blocks.iter().enumerate() {
        if let BlockDofs::Deformable = blk.dofs {
            for node in blk.nodes.clone() {
                if on_contact[node as usize] {
                    continue;
                }
                for &d in &mesh.node_dofs[node as usize] {
                    if d != dfem_kernels::CONSTRAINED {
                        group[d as usize] = b as u32;
                    }
                }
            }
        }
    }
    group
}

/// The movable blocks partitioned into `parts` subdomains, as the part of every unknown
/// ([`LinearBackend::set_partition`]): METIS recursive bisection
/// ([`dfem_kernels::metis_partition_graph`]; parts numbered along the bisections, which
/// `faer-substructured` nests its interfaces by) on the block adjacency graph — one vertex
/// per block with unknowns, weighted by its number of unknowns (3 for a rigid block, 2
/// per free node of a deformable one), one edge per pair of blocks joined by contacts,
/// weighted by their number of contacts. A block's unknowns all go to one part, so every
/// cut between parts runs along joints, and METIS keeps the contacts cut (and so the
/// interface unknowns) few while balancing the unknowns. Fixed blocks have no unknowns
/// and do not take part. Deterministic (METIS' fixed seed). The one place where dfem
/// decides which subdomain a block belongs to: the substructured direct solver's
/// subdomains and a distributed PETSc's ranks both come from here.
pub fn block_partition(mesh: &crate::mesh::Mesh, parts: usize) -> Result<Vec<u32>, SolveError> {
    use crate::mesh::BlockDofs;
    // the unknowns of each block
    let mut unknowns: Vec<Vec<u32>> = vec![Vec::new(); mesh.blocks.len()];
    for (b, list) in mesh.blocks.iter().zip(unknowns.iter_mut()) {
        match b.dofs {
            BlockDofs::Fixed => {}
            BlockDofs::Rigid { first, .. } => list.extend(first..first + 3),
            BlockDofs::Deformable => {
                for node in b.nodes.clone() {
                    list.extend(
                        mesh.node_dofs[node as usize]
                            .iter()
                            .copied()
                            .filter(|&d| d != dfem_kernels::CONSTRAINED),
                    );
                }
            }
        }
    }
    // graph vertices: the blocks with unknowns
    let mut vertex = vec![u32::MAX; mesh.blocks.len()];
    let mut weights = Vec::new();
    for (b, list) in unknowns.iter().enumerate() {
        if !list.is_empty() {
            vertex[b] = weights.len() as u32;
            weights.push(list.len() as u32);
        }
    }
    let edges: Vec<(u32, u32, u32)> = mesh
        .contacts
        .iter()
        .map(|c| (vertex[c.block_l as usize], vertex[c.block_m as usize]))
        .filter(|&(a, b)| a != u32::MAX && b != u32::MAX && a != b)
        .map(|(a, b)| (a, b, 1))
        .collect();
    let block_part = dfem_kernels::metis_partition_graph(&weights, &edges, parts)?;
    let mut part = vec![0u32; mesh.n_dofs];
    for (b, list) in unknowns.iter().enumerate() {
        if vertex[b] != u32::MAX {
            let p = block_part[vertex[b] as usize];
            for &d in list {
                part[d as usize] = p;
            }
        }
    }
    Ok(part)
}

/// Hands `backend` what dfem knows of the structure of its matrices, before the first
/// factorization: the blocks' rigid-body modes ([`rigid_body_modes`], the near-null
/// space) and, if the backend asks for a partition into k parts
/// ([`LinearBackend::partition_parts`]), the blocks' partition ([`block_partition`]).
/// `dfem run`, `dfem bench-solvers` and the tests all go through here.
pub fn configure(
    backend: &mut dyn LinearBackend,
    mesh: &crate::mesh::Mesh,
) -> Result<(), SolveError> {
    configure_with(backend, mesh, None)
}

/// [`configure`], plus `known`: a partition of the unknowns into `known.0` parts already
/// computed, handed over instead of computing it again when the backend asks for as many.
fn configure_with(
    backend: &mut dyn LinearBackend,
    mesh: &crate::mesh::Mesh,
    known: Option<(usize, &[u32])>,
) -> Result<(), SolveError> {
    backend.set_near_null_space(&rigid_body_modes(mesh))?;
    backend.set_interiors(&interior_groups(mesh))?;
    match (backend.partition_parts(), known) {
        (Some(k), Some((parts, part))) if k == parts => backend.set_partition(part)?,
        (Some(k), _) => backend.set_partition(&block_partition(mesh, k)?)?,
        (None, _) => {}
    }
    Ok(())
}

/// [`configure`] for the run of this process (`dfem run`). Under `mpirun` with N > 1
/// processes (feature `mpi`), also distributes the assembly: the unknowns are split by
/// [`block_partition`] into N parts, returned with this process's rank
/// ([`crate::assembly::Ranks`], for the analysis to pass to
/// [`crate::assembly::System::distributed`]: each process's assembly evaluates only the
/// elements of its own rows, then the processes exchange their rows), and a distributed
/// backend (one that asks for N parts: PETSc, MUMPS) gets the same partition for its
/// rows. Serial: [`configure`], and `None`.
pub fn configure_run(
    backend: &mut dyn LinearBackend,
    mesh: &crate::mesh::Mesh,
) -> Result<Option<crate::assembly::Ranks>, SolveError> {
    let (rank, size) = dfem_ffi::process_rank();
    if size <= 1 {
        return configure(backend, mesh).map(|()| None);
    }
    let part = block_partition(mesh, size)?;
    // every process must split the rows alike (METIS is deterministic for the same
    // input; checked, since a mismatch would garble the exchanged rows)
    let h = part
        .iter()
        .fold(0x811c_9dc5u32, |h, &p| (h ^ p).wrapping_mul(0x0100_0193));
    let mut all = vec![0.0; size];
    dfem_ffi::allgather(&[f64::from(h)], &vec![1; size], &mut all).map_err(SolveError::Other)?;
    if all.iter().any(|&x| x != f64::from(h)) {
        return Err(SolveError::Other(
            "the processes computed different block partitions (METIS differs between \
             them); run every process on the same machine type"
                .into(),
        ));
    }
    configure_with(backend, mesh, Some((size, &part)))?;
    Ok(Some(crate::assembly::Ranks {
        part,
        rank: rank as u32,
        size: size as u32,
    }))
}

pub mod bench;
pub mod reuse;
