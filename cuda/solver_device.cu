// Device (CUDA) instantiation of the solver: launches only, no physics.
#include "cuda/exec_device.cuh"
#include "cuda/particles_device.hpp"
#include "solver/solver_impl.hpp"

namespace sphdem {

template class Solver<Device>;

std::unique_ptr<SolverBase> make_device_solver(const Scene& scene, ParticleSet<Host> particles,
                                               Real c0, std::shared_ptr<Exchange> ex) {
  return std::make_unique<Solver<Device>>(scene, std::move(particles), c0, std::move(ex));
}

}  // namespace sphdem
