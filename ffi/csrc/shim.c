#define _GNU_SOURCE
#include <dlfcn.h>
#include "shim.h"
#ifdef DFEM_PETSC
MPI_Comm dfem_comm_self(void) { return MPI_COMM_SELF; }
MPI_Op dfem_op_sum(void) { return MPI_SUM; }
MPI_Op dfem_op_max(void) { return MPI_MAX; }
MPI_Datatype dfem_type_double(void) { return MPI_DOUBLE; }
MPI_Datatype dfem_type_int(void) { return MPI_INT; }
void dfem_mpi_finalize(void) {
  int init = 0, fin = 0;
  MPI_Initialized(&init);
  MPI_Finalized(&fin);
  if (init && !fin) MPI_Finalize();
}
#endif

#ifdef DFEM_MUMPS
#include <dmumps_c.h>
size_t dfem_dmumps_struc_size(void) { return sizeof(DMUMPS_STRUC_C); }
size_t dfem_dmumps_offset_info(void) { return offsetof(DMUMPS_STRUC_C, info); }
size_t dfem_dmumps_offset_pivnul_list(void) { return offsetof(DMUMPS_STRUC_C, pivnul_list); }
size_t dfem_dmumps_offset_metis_options(void) { return offsetof(DMUMPS_STRUC_C, metis_options); }
#ifdef DFEM_MUMPS_MPI
#include <mpi.h>
int dfem_mumps_comm(void) {
  int init = 0;
  MPI_Initialized(&init);
  if (!init) MPI_Init(NULL, NULL);
  return (int)MPI_Comm_c2f(MPI_COMM_SELF);
}
int dfem_mumps_comm_world(void) { return (int)MPI_Comm_c2f(MPI_COMM_WORLD); }
#else
int dfem_mumps_comm(void) { return -987654; }
int dfem_mumps_comm_world(void) { return -987654; }
#endif
#else
size_t dfem_dmumps_struc_size(void) { return 0; }
size_t dfem_dmumps_offset_info(void) { return 0; }
size_t dfem_dmumps_offset_pivnul_list(void) { return 0; }
size_t dfem_dmumps_offset_metis_options(void) { return 0; }
int dfem_mumps_comm(void) { return 0; }
int dfem_mumps_comm_world(void) { return 0; }
#endif

void dfem_blas_single_thread(void) {
  void (*set)(int) = (void (*)(int))dlsym(RTLD_DEFAULT, "openblas_set_num_threads");
  if (set) set(1);
}
