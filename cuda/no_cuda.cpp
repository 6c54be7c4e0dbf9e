// Stand-ins for the CUDA execution space when sphdem is built with SPHDEM_ENABLE_CUDA=OFF.
#include "core/error.hpp"
#include "cuda/device.hpp"

namespace sphdem::cuda {

bool compiled_with_cuda() {
  return false;
}
std::vector<GpuInfo> list_gpus(std::string* why) {
  if (why) *why = "built without CUDA (SPHDEM_ENABLE_CUDA=OFF)";
  return {};
}
namespace {
[[noreturn]] void unavailable() {
  throw RuntimeFault("sphdem was built without CUDA (SPHDEM_ENABLE_CUDA=OFF)");
}
}  // namespace
void select_device(int) {
  unavailable();
}
int current_device() {
  return -1;
}
void* device_alloc(std::size_t) {
  unavailable();
}
void device_free(void*) noexcept {}
void release_cached_memory() {}
void copy_to_device(void*, const void*, std::size_t) {
  unavailable();
}
void copy_to_host(void*, const void*, std::size_t) {
  unavailable();
}
void copy_device_to_device(void*, const void*, std::size_t) {
  unavailable();
}
void synchronize() {}
void* pinned_alloc(std::size_t) {
  unavailable();
}
void pinned_free(void*) noexcept {}

}  // namespace sphdem::cuda

#include "solver/solver.hpp"

namespace sphdem {
std::unique_ptr<SolverBase> make_device_solver(const Scene&, ParticleSet<Host>, Real,
                                               std::shared_ptr<Exchange>) {
  throw RuntimeFault("sphdem was built without CUDA (SPHDEM_ENABLE_CUDA=OFF): no device solver");
}
}  // namespace sphdem
