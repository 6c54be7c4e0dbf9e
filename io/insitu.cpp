#include "io/insitu.hpp"

#include "core/error.hpp"

namespace sphdem {

#ifdef SPHDEM_HAVE_CATALYST
// io/catalyst_adaptor.cpp
std::unique_ptr<InSituAdaptor> make_catalyst_adaptor(const Scene& scene,
                                                     const std::string& out_dir);
bool catalyst_compiled() {
  return true;
}
#else
bool catalyst_compiled() {
  return false;
}
#endif

std::unique_ptr<InSituAdaptor> make_insitu_adaptor(const Scene& scene, const std::string& out_dir) {
  if (scene.insitu.scripts.empty()) return std::make_unique<NullInSituAdaptor>();
#ifdef SPHDEM_HAVE_CATALYST
  return make_catalyst_adaptor(scene, out_dir);
#else
  (void)out_dir;
  throw InputError(scene.source +
                   ": insitu: this sphdem was built without Catalyst; rebuild with "
                   "-DSPHDEM_ENABLE_CATALYST=ON (ParaView 5.11: paraview-dev python3-paraview), or "
                   "remove the insitu section");
#endif
}

}  // namespace sphdem
