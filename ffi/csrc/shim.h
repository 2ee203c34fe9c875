/* Small C helpers for what Rust cannot name directly: MPI handles that are macros in
 * OpenMPI, and the layout of MUMPS' DMUMPS_STRUC_C for checking the hand-written binding. */
#ifndef DFEM_SHIM_H
#define DFEM_SHIM_H
#include <stddef.h>
#ifdef DFEM_PETSC
#include <mpi.h>
/* MPI_COMM_SELF (a macro in OpenMPI). */
MPI_Comm dfem_comm_self(void);
/* MPI_SUM, MPI_DOUBLE, MPI_LONG_LONG (macros in OpenMPI). */
MPI_Op dfem_op_sum(void);
MPI_Op dfem_op_max(void);
MPI_Datatype dfem_type_double(void);
MPI_Datatype dfem_type_int(void);
/* MPI_Finalize when MPI is initialized and not yet finalized. */
void dfem_mpi_finalize(void);
#endif
/* sizeof(DMUMPS_STRUC_C) and offsets of a few of its members, 0 without MUMPS. */
size_t dfem_dmumps_struc_size(void);
size_t dfem_dmumps_offset_info(void);
size_t dfem_dmumps_offset_pivnul_list(void);
size_t dfem_dmumps_offset_metis_options(void);
/* Fortran handle of MPI_COMM_SELF for MUMPS' COMM_FORTRAN (initializes MPI when needed in
 * the MPI build; -987654, MUMPS' "use comm world", in the sequential one). */
int dfem_mumps_comm(void);
int dfem_mumps_comm_world(void);
/* OpenBLAS (behind MUMPS and PETSc) on one thread, if it is the BLAS loaded: results then do
 * not depend on its thread count, and its spinning threads do not compete with rayon's. */
void dfem_blas_single_thread(void);
#endif
