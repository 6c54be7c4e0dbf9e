// Small helpers over the HDF5 C API shared by checkpoints and frames: element types, collective
// hyperslab writes/reads of one field, scalar attributes. Host code only (io/). Errors throw
// InputError prefixed with `label` (e.g. "checkpoint 'out/checkpoint_0000000100.h5'").
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <string>

#include "core/error.hpp"
#include "core/types.hpp"

namespace sphdem::h5 {

// HDF5 memory type and component count of a field element.
template <class T>
struct Type;
template <>
struct Type<double> {
  static hid_t id() { return H5T_NATIVE_DOUBLE; }
  static constexpr int n = 1;
};
template <>
struct Type<float> {
  static hid_t id() { return H5T_NATIVE_FLOAT; }
  static constexpr int n = 1;
};
template <>
struct Type<std::uint64_t> {
  static hid_t id() { return H5T_NATIVE_UINT64; }
  static constexpr int n = 1;
};
template <>
struct Type<std::int32_t> {
  static hid_t id() { return H5T_NATIVE_INT32; }
  static constexpr int n = 1;
};
template <>
struct Type<Vec3> {
  static hid_t id() { return Type<Real>::id(); }
  static constexpr int n = 3;
};

[[noreturn]] inline void fail(const std::string& label, const std::string& what) {
  throw InputError(label + ": " + what);
}

inline void check(herr_t e, const std::string& label, const char* what) {
  if (e < 0) fail(label, std::string("HDF5 error in ") + what);
}

template <class T>
inline void write_attr(hid_t obj, const char* name, hid_t type, T v) {
  hid_t sp = H5Screate(H5S_SCALAR);
  hid_t a = H5Acreate2(obj, name, type, sp, H5P_DEFAULT, H5P_DEFAULT);
  H5Awrite(a, type, &v);
  H5Aclose(a);
  H5Sclose(sp);
}

template <class T>
inline T read_attr(hid_t obj, const char* name, hid_t type, const std::string& label) {
  if (H5Aexists(obj, name) <= 0) fail(label, std::string("attribute '") + name + "' is missing");
  T v{};
  hid_t a = H5Aopen(obj, name, H5P_DEFAULT);
  check(H5Aread(a, type, &v), label, name);
  H5Aclose(a);
  return v;
}

// A dataset of `total` rows (N, or N x 3 for Vec3) written collectively; this rank's `count`
// rows go at `offset`.
template <class T>
inline void write_field(hid_t group, const char* name, const T* data, Index count, Index offset,
                        Index total, const std::string& label) {
  constexpr int ncomp = Type<T>::n;
  const int rank = ncomp == 1 ? 1 : 2;
  hsize_t dims[2] = {hsize_t(total), hsize_t(ncomp)};
  hid_t fs = H5Screate_simple(rank, dims, nullptr);
  hid_t ds = H5Dcreate2(group, name, Type<T>::id(), fs, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (ds < 0) fail(label, std::string("cannot create dataset ") + name);
  hsize_t start[2] = {hsize_t(offset), 0}, cnt[2] = {hsize_t(count), hsize_t(ncomp)};
  H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, nullptr, cnt, nullptr);
  hid_t ms = H5Screate_simple(rank, cnt, nullptr);
  if (count == 0) {
    H5Sselect_none(fs);
    H5Sselect_none(ms);
  }
  hid_t xfer = H5Pcreate(H5P_DATASET_XFER);
  H5Pset_dxpl_mpio(xfer, H5FD_MPIO_COLLECTIVE);
  // An empty dataset (no boundary particles anywhere) has no storage: HDF5 1.10 fails a
  // collective write to it ("addr overflow"). `total` is global, so every rank skips it.
  const herr_t e = total > 0 ? H5Dwrite(ds, Type<T>::id(), ms, fs, xfer, data) : herr_t(0);
  H5Pclose(xfer);
  H5Sclose(ms);
  H5Sclose(fs);
  H5Dclose(ds);
  check(e, label, name);
}

template <class T>
inline void read_field(hid_t group, const char* name, T* data, Index count, Index offset,
                       const std::string& label) {
  constexpr int ncomp = Type<T>::n;
  const int rank = ncomp == 1 ? 1 : 2;
  if (H5Lexists(group, name, H5P_DEFAULT) <= 0)
    fail(label, std::string("field '") + name + "' is missing");
  hid_t ds = H5Dopen2(group, name, H5P_DEFAULT);
  hid_t fs = H5Dget_space(ds);
  hsize_t start[2] = {hsize_t(offset), 0}, cnt[2] = {hsize_t(count), hsize_t(ncomp)};
  H5Sselect_hyperslab(fs, H5S_SELECT_SET, start, nullptr, cnt, nullptr);
  hid_t ms = H5Screate_simple(rank, cnt, nullptr);
  if (count == 0) {
    H5Sselect_none(fs);
    H5Sselect_none(ms);
  }
  hid_t xfer = H5Pcreate(H5P_DATASET_XFER);
  H5Pset_dxpl_mpio(xfer, H5FD_MPIO_COLLECTIVE);
  hsize_t extent[2] = {0, 0};
  H5Sget_simple_extent_dims(fs, extent, nullptr);
  // An empty dataset has no storage to read (see write_field); the extent is the same on all ranks.
  const herr_t e = extent[0] > 0 ? H5Dread(ds, Type<T>::id(), ms, fs, xfer, data) : herr_t(0);
  H5Pclose(xfer);
  H5Sclose(ms);
  H5Sclose(fs);
  H5Dclose(ds);
  if (e < 0) fail(label, std::string("cannot read field '") + name + "' (truncated file?)");
}

// Opens a file collectively on MPI_COMM_WORLD for create (truncate) or read.
hid_t create_file(const std::string& path);
hid_t open_file_read(const std::string& path);

}  // namespace sphdem::h5
