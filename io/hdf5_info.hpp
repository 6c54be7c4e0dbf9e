// HDF5 library facts for `sphdem info`.
#pragma once
#include <string>
namespace sphdem {
std::string hdf5_version();  // "1.10.8 (parallel)"
}
