#include "io/frames.hpp"

#include <hdf5.h>
#include <mpi.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/checkpoint.hpp"
#include "io/h5_util.hpp"

namespace sphdem {

namespace {

bool in_region(const FrameParams& p, const Vec3& x, int dim) {
  if (!p.region) return true;
  for (int k = 0; k < 3; ++k) {
    if (dim == 2 && k == 1) continue;
    if (x[k] < p.region_lo[k] || x[k] > p.region_hi[k]) return false;
  }
  return true;
}

// The selected slots of [begin, end) gathered into contiguous host arrays.
struct Selection {
  std::vector<Index> slots;
};

// role: 0 any slot of the range, 1 walls only, 2 grains only (boundary slots hold both, sorted
// together by cell; the body field tells them apart).
Selection select(const ParticleSet<Host>& ps, Index begin, Index end, const FrameParams& p, int dim,
                 int role = 0) {
  Selection s;
  for (Index i = begin; i < end; ++i) {
    if (role != 0 && is_grain_body(ps.body[std::size_t(i)]) != (role == 2)) continue;
    if (in_region(p, ps.pos[i], dim)) s.slots.push_back(i);
  }
  return s;
}

template <class T>
std::vector<T> gather(const Buffer<T, Host>& b, const Selection& s) {
  std::vector<T> out;
  out.reserve(s.slots.size());
  for (Index i : s.slots) out.push_back(b[std::size_t(i)]);
  return out;
}

template <class T>
void write_block_field(hid_t grp, const char* name, const std::vector<T>& v, Index total,
                       Index offset, const std::string& label) {
  h5::write_field(grp, name, v.data(), Index(v.size()), offset, total, label);
}

const char* xdmf_number_type() {
  return sizeof(Real) == 8 ? "Float\" Precision=\"8" : "Float\" Precision=\"4";
}

}  // namespace

FrameWriter::FrameWriter(const std::string& dir, const FrameParams& params, int dim)
    : dir_(dir), params_(params), dim_(dim) {}

void FrameWriter::write(Real time, const ParticleSet<Host>& ps_const) {
  auto& ps = const_cast<ParticleSet<Host>&>(ps_const);
  char name[64];
  std::snprintf(name, sizeof(name), "frame_%05d.h5", int(frames_.size()));
  const std::string path = dir_ + "/" + name;
  const std::string label = "frame '" + path + "'";
  hid_t f = h5::create_file(path);
  if (f < 0) throw InputError("cannot create frame file '" + path + "'");
  h5::write_attr<double>(f, "time", H5T_NATIVE_DOUBLE, time);
  Frame fr{time, name, 0, 0, 0};
  Index grains = ps.n_grain, any_grains = 0;
  MPI_Allreduce(&grains, &any_grains, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
  const int groups = params_.boundary ? (any_grains > 0 ? 3 : 2) : 1;
  for (int g = 0; g < groups; ++g) {
    const Selection sel = g == 0 ? select(ps, 0, ps.n_fluid, params_, dim_)
                                 : select(ps, ps.wall_begin(), ps.size(), params_, dim_, g);
    Index local = Index(sel.slots.size()), total = 0, offset = 0;
    MPI_Allreduce(&local, &total, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
    MPI_Exscan(&local, &offset, 1, MPI_INT64_T, MPI_SUM, MPI_COMM_WORLD);
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0) offset = 0;
    static const char* const kGroups[] = {"fluid", "walls", "grains"};
    hid_t grp = H5Gcreate2(f, kGroups[g], H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    write_block_field(grp, "pos", gather(ps.pos, sel), total, offset, label);
    if (g == 0) {
      for (const std::string& fld : params_.fields) {
        ps.for_each_field([&](const char* n, auto& b) {
          if (fld == n) write_block_field(grp, n, gather(b, sel), total, offset, label);
        });
      }
      fr.n_fluid = total;
    } else {
      write_block_field(grp, "press", gather(ps.press, sel), total, offset, label);
      write_block_field(grp, "body", gather(ps.body, sel), total, offset, label);
      if (g == 2) write_block_field(grp, "vel", gather(ps.vel, sel), total, offset, label);
      (g == 1 ? fr.n_wall : fr.n_grain) = total;
    }
    H5Gclose(grp);
  }
  H5Fclose(f);
  frames_.push_back(fr);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) write_index();
}

void FrameWriter::adopt_existing(Real up_to_time) {
  // Re-read the times of frames written before a restart, keeping those up to the restart time.
  for (int k = 0;; ++k) {
    char name[64];
    std::snprintf(name, sizeof(name), "frame_%05d.h5", k);
    const std::string path = dir_ + "/" + name;
    if (!std::filesystem::exists(path)) break;
    hid_t f = h5::open_file_read(path);
    if (f < 0) break;
    Frame fr{0, name, 0, 0, 0};
    fr.time = h5::read_attr<double>(f, "time", H5T_NATIVE_DOUBLE, path);
    for (int g = 0; g < 3; ++g) {
      const char* gname = g == 0 ? "fluid" : (g == 1 ? "walls" : "grains");
      if (H5Lexists(f, gname, H5P_DEFAULT) <= 0) continue;
      hid_t ds = H5Dopen2(f, (std::string(gname) + "/pos").c_str(), H5P_DEFAULT);
      hid_t sp = H5Dget_space(ds);
      hsize_t dims[2] = {0, 0};
      H5Sget_simple_extent_dims(sp, dims, nullptr);
      (g == 0 ? fr.n_fluid : (g == 1 ? fr.n_wall : fr.n_grain)) = Index(dims[0]);
      H5Sclose(sp);
      H5Dclose(ds);
    }
    H5Fclose(f);
    if (fr.time > up_to_time + 1e-12) break;
    frames_.push_back(fr);
  }
}

void FrameWriter::write_index() const {
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n"
    << "<Grid Name=\"sphdem\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  auto attribute = [&](const Frame& fr, const char* block, const std::string& name, Index n,
                       int ncomp, const char* type) {
    x << "    <Attribute Name=\"" << name << "\" AttributeType=\""
      << (ncomp == 3 ? "Vector" : "Scalar") << "\" Center=\"Node\">\n      <DataItem Dimensions=\""
      << n;
    if (ncomp == 3) x << " 3";
    x << "\" NumberType=\"" << type << "\" Format=\"HDF\">" << fr.file << ":/" << block << "/"
      << name << "</DataItem>\n    </Attribute>\n";
  };
  for (const Frame& fr : frames_) {
    x << " <Grid GridType=\"Collection\" CollectionType=\"Spatial\">\n  <Time Value=\"" << fr.time
      << "\" />\n";
    for (int g = 0; g < 3; ++g) {
      const Index n = g == 0 ? fr.n_fluid : (g == 1 ? fr.n_wall : fr.n_grain);
      if (g >= 1 && !params_.boundary) continue;
      if (g == 2 && n == 0) continue;
      const char* block = g == 0 ? "fluid" : (g == 1 ? "walls" : "grains");
      x << "  <Grid Name=\"" << block << "\" GridType=\"Uniform\">\n"
        << "   <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n << "\" />\n"
        << "   <Geometry GeometryType=\"XYZ\">\n    <DataItem Dimensions=\"" << n
        << " 3\" NumberType=\"" << xdmf_number_type() << "\" Format=\"HDF\">" << fr.file << ":/"
        << block << "/pos</DataItem>\n   </Geometry>\n";
      if (g == 0) {
        for (const std::string& fld : params_.fields) {
          const bool vec = fld == "vel" || fld == "acc";
          const char* type = fld == "id" ? "UInt\" Precision=\"8" : xdmf_number_type();
          attribute(fr, block, fld, n, vec ? 3 : 1, type);
        }
      } else {
        attribute(fr, block, "press", n, 1, xdmf_number_type());
        attribute(fr, block, "body", n, 1, "Int\" Precision=\"4");
        if (g == 2) attribute(fr, block, "vel", n, 3, xdmf_number_type());
      }
      x << "  </Grid>\n";
    }
    x << " </Grid>\n";
  }
  x << "</Grid>\n</Domain>\n</Xdmf>\n";
  const std::string path = dir_ + "/frames.xdmf", tmp = path + ".tmp";
  {
    std::ofstream f(tmp);
    f << x.str();
  }
  std::filesystem::rename(tmp, path);
}

}  // namespace sphdem
