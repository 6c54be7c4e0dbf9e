#include "io/hdf5_info.hpp"

#include <hdf5.h>

#include <sstream>

namespace sphdem {
std::string hdf5_version() {
  unsigned a = 0, b = 0, c = 0;
  H5get_libversion(&a, &b, &c);
  std::ostringstream os;
  os << a << "." << b << "." << c;
#ifdef H5_HAVE_PARALLEL
  os << " (parallel)";
#else
  os << " (serial)";
#endif
  return os.str();
}
}  // namespace sphdem
