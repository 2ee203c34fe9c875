/* The PETSc API seen by bindgen (build.rs): KSP pulls in Mat, Vec, PC and MPI. */
#include <petscksp.h>
#include "shim.h"
