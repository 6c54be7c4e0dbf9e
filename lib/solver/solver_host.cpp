// Host (OpenMP) instantiation of the solver.
#include "solver/solver_impl.hpp"

namespace sphdem {

template class Solver<Host>;

std::unique_ptr<SolverBase> make_host_solver(const Scene& scene, ParticleSet<Host> particles,
                                             Real c0, std::shared_ptr<Exchange> ex) {
  return std::make_unique<Solver<Host>>(scene, std::move(particles), c0, std::move(ex));
}

}  // namespace sphdem
