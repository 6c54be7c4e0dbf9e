#include "decomposition/parallel_env.hpp"

#include <mpi.h>
#include <petscsys.h>

#include "core/error.hpp"

namespace sphdem {

ParallelEnv::ParallelEnv(int* argc, char*** argv) {
  if (PetscInitialize(argc, argv, nullptr, nullptr) != 0)
    throw RuntimeFault("PetscInitialize failed");
  MPI_Comm_rank(PETSC_COMM_WORLD, &rank_);
  MPI_Comm_size(PETSC_COMM_WORLD, &size_);
  MPI_Comm local;
  MPI_Comm_split_type(PETSC_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &local);
  MPI_Comm_rank(local, &local_rank_);
  MPI_Comm_free(&local);
}

ParallelEnv::~ParallelEnv() {
  PetscFinalize();
}

std::string petsc_version() {
  char buf[256];
  PetscGetVersion(buf, sizeof(buf));
  return buf;
}

std::string mpi_version() {
  char buf[MPI_MAX_LIBRARY_VERSION_STRING];
  int len = 0;
  MPI_Get_library_version(buf, &len);
  std::string s(buf, std::size_t(len));
  const auto nl = s.find_first_of("\n,");
  return nl == std::string::npos ? s : s.substr(0, nl);
}

}  // namespace sphdem
