//! Links the system MUMPS and PETSc (Debian's `libmumps-seq-dev`, `libmumps-dev`,
//! `petsc-dev`) when the matching features are on, compiles the small C shim of
//! `csrc/shim.c` (layout checks of the MUMPS structure, MPI handles that are macros in C) and
//! runs bindgen over `csrc/petsc.h` for the PETSc binding. Without features it does nothing.

use std::env;
use std::path::PathBuf;

fn pkg_config(args: &[&str]) -> Option<String> {
    let out = std::process::Command::new("pkg-config")
        .args(args)
        .output()
        .ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

fn include_dirs(cflags: &str) -> Vec<PathBuf> {
    cflags
        .split_whitespace()
        .filter_map(|f| f.strip_prefix("-I"))
        .map(PathBuf::from)
        .collect()
}

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=csrc");
    let mumps = env::var_os("CARGO_FEATURE_MUMPS").is_some();
    let petsc = env::var_os("CARGO_FEATURE_PETSC").is_some();
    if !mumps && !petsc {
        return;
    }
    let mut shim = cc_build();
    shim.file("csrc/shim.c");
    let mut includes = Vec::new();
    if petsc {
        let cflags = pkg_config(&["--cflags", "PETSc"]).unwrap_or_else(|| {
            panic!(
                "feature `petsc`: pkg-config cannot find PETSc; install it with \
                 `apt-get install -y petsc-dev libclang-dev` (Debian/Ubuntu)"
            )
        });
        let libdir = pkg_config(&["--variable=libdir", "PETSc"]).unwrap_or_default();
        includes.extend(include_dirs(&cflags));
        includes.extend(include_dirs(
            &pkg_config(&["--cflags", "ompi-c"]).unwrap_or_default(),
        ));
        println!("cargo:rustc-link-search=native={libdir}");
        println!("cargo:rustc-link-arg=-Wl,-rpath,{libdir}");
        println!("cargo:rustc-link-lib=dylib=petsc_real");
        println!("cargo:rustc-link-lib=dylib=mpi");
        shim.define("DFEM_PETSC", None);
        bind_petsc(&includes);
    }
    if mumps {
        shim.define("DFEM_MUMPS", None);
        if petsc {
            // PETSc links the MPI build of MUMPS; the sequential one would clash with it.
            shim.define("DFEM_MUMPS_MPI", None);
            println!("cargo:rustc-link-lib=dylib=dmumps");
            println!("cargo:rustc-link-lib=dylib=mumps_common");
            println!("cargo:rustc-cfg=mumps_mpi");
        } else {
            println!("cargo:rustc-link-lib=dylib=dmumps_seq");
            println!("cargo:rustc-link-lib=dylib=mumps_common_seq");
        }
    }
    println!("cargo::rustc-check-cfg=cfg(mumps_mpi)");
    for i in &includes {
        shim.include(i);
    }
    shim.compile("dfem_ffi_shim");
}

fn cc_build() -> cc::Build {
    let mut b = cc::Build::new();
    b.warnings(true);
    b
}

/// PETSc's API is bound with bindgen rather than by hand: its types depend on how the
/// installed PETSc was configured (`PetscInt` 32 or 64 bits, `PetscScalar`, `MPI_Comm` a
/// pointer in OpenMPI but an int in MPICH), and the structures are opaque handles, so
/// generating the declarations from the installed headers keeps them right on any build.
/// The allowlist keeps the output to the ~50 functions used.
#[cfg(feature = "petsc")]
fn bind_petsc(includes: &[PathBuf]) {
    let mut b = bindgen::Builder::default()
        .header("csrc/petsc.h")
        .allowlist_function("Petsc(Initialize|Initialized|Finalize|Finalized|OptionsInsertString|OptionsCreate|OptionsDestroy|ObjectSetOptions|MemoryGetCurrentUsage|MallocGetCurrentUsage)")
        .allowlist_function("Mat(Create|CreateVecs|SetSizes|SetType|SeqAIJSetPreallocationCSR|MPIAIJSetPreallocationCSR|SetValues|AssemblyBegin|AssemblyEnd|Destroy|SetNearNullSpace|NullSpaceCreate|NullSpaceDestroy|GetInfo|SetOption|SetBlockSize|GetOwnershipRange)")
        .allowlist_function("Vec(Create|CreateMPI|CreateMPIWithArray|SetSizes|GetArray|RestoreArray|Destroy|Duplicate|ScatterCreateToAll|ScatterBegin|ScatterEnd|ScatterDestroy|Normalize|Dot|AXPY|Scale)")
        .allowlist_function("KSP(Create|SetOperators|SetType|GetType|GetPC|SetTolerances|SetFromOptions|SetUp|Solve|GetIterationNumber|GetConvergedReason|GetResidualNorm|Destroy|SetNormType|SetInitialGuessNonzero)")
        .allowlist_function("PC(SetType|GetType|FactorGetMatrix)")
        .allowlist_function("MPI_Comm_(rank|size)")
        .allowlist_function("MPI_(Allreduce|Allgatherv|Bcast|Barrier)")
        .allowlist_function("dfem_.*")
        .allowlist_var("PETSC_COMM_WORLD")
        .allowlist_type("MatInfo|MatInfoType|InsertMode|ScatterMode|MatAssemblyType|KSPConvergedReason|MatOption|PetscBool")
        .blocklist_type("FILE|_IO_.*")
        .derive_default(true)
        .layout_tests(false)
        .generate_comments(false)
        .clang_arg("-DDFEM_PETSC");
    for i in includes {
        b = b.clang_arg(format!("-I{}", i.display()));
    }
    let out = PathBuf::from(env::var("OUT_DIR").unwrap()).join("petsc_bindings.rs");
    b.generate()
        .expect("bindgen over csrc/petsc.h failed (is libclang-dev installed?)")
        .write_to_file(out)
        .expect("cannot write the PETSc bindings");
}

#[cfg(not(feature = "petsc"))]
fn bind_petsc(_: &[PathBuf]) {}
