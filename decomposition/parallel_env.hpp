// MPI and PETSc start-up and shutdown for the whole process (PetscInitialize calls MPI_Init).
// Decomposition proper (DMDA ownership, DMSwarm migration, PetscSF halo) builds on this.
#pragma once

#include <string>

namespace sphdem {

class ParallelEnv {
 public:
  ParallelEnv(int* argc, char*** argv);
  ~ParallelEnv();
  ParallelEnv(const ParallelEnv&) = delete;
  ParallelEnv& operator=(const ParallelEnv&) = delete;
  int rank() const { return rank_; }
  int size() const { return size_; }
  // Node-local rank (MPI_Comm_split_type shared), for GPU selection.
  int local_rank() const { return local_rank_; }

 private:
  int rank_ = 0, size_ = 1, local_rank_ = 0;
};

std::string petsc_version();
std::string mpi_version();

}  // namespace sphdem
