//! FFI backends (MUMPS, PETSc) behind features; see issue 7.
