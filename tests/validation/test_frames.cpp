// ParaView frames: the fluid, the walls and the grains are separate blocks of the XDMF index, each
// with its point count and arrays, and a run without grains has no grains block.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "io/checkpoint.hpp"
#include "io/frames.hpp"

namespace sphdem {
namespace {

namespace fs = std::filesystem;

ParticleSet<Host> set_with(Index nf, Index nw, Index ng) {
  ParticleSet<Host> ps;
  ps.n_fluid = nf;
  ps.n_wall = nw;
  ps.n_grain = ng;
  ps.resize(nf + nw + ng);
  for (Index i = 0; i < ps.size(); ++i) {
    ps.id[std::size_t(i)] = GlobalId(i);
    ps.pos[std::size_t(i)] = Vec3(Real(i), 0, Real(0.5) * Real(i));
    ps.vel[std::size_t(i)] = Vec3(Real(i) * 10, 0, 0);
    // Fluid -1, walls their solid index, grain g kGrainBodyBase - g; walls and grains are
    // interleaved, as the solver's sort by cell leaves them.
    const Index b = i - nf;
    const bool grain = i >= nf && (b % 2 == 1 ? b / 2 < ng : b - ng >= nw);
    ps.body[std::size_t(i)] = i < nf ? -1 : (grain ? kGrainBodyBase - 1 : 0);
  }
  return ps;
}

std::string read_text(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

hsize_t rows(const std::string& file, const char* dataset) {
  hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t ds = H5Dopen2(f, dataset, H5P_DEFAULT);
  hid_t sp = H5Dget_space(ds);
  hsize_t dims[2] = {0, 0};
  H5Sget_simple_extent_dims(sp, dims, nullptr);
  H5Sclose(sp);
  H5Dclose(ds);
  H5Fclose(f);
  return dims[0];
}

TEST(Frames, FluidWallsAndGrainsAreSeparateBlocks) {
  ensure_mpi();
  const std::string dir = "frames_blocks";
  fs::remove_all(dir);
  fs::create_directories(dir);
  FrameParams p;
  p.every = 0.1;
  FrameWriter w(dir, p, 3);
  w.write(0, set_with(10, 6, 4));
  const std::string x = read_text(dir + "/frames.xdmf");
  for (const char* block : {"fluid", "walls", "grains"})
    EXPECT_NE(x.find(std::string("Grid Name=\"") + block + "\""), std::string::npos) << block;
  EXPECT_NE(x.find("frame_00000.h5:/grains/vel"), std::string::npos);
  EXPECT_EQ(rows(dir + "/frame_00000.h5", "fluid/pos"), 10u);
  EXPECT_EQ(rows(dir + "/frame_00000.h5", "walls/pos"), 6u);
  EXPECT_EQ(rows(dir + "/frame_00000.h5", "grains/pos"), 4u);
  EXPECT_EQ(rows(dir + "/frame_00000.h5", "grains/body"), 4u);
}

TEST(Frames, NoGrainsNoGrainsBlock) {
  ensure_mpi();
  const std::string dir = "frames_no_grains";
  fs::remove_all(dir);
  fs::create_directories(dir);
  FrameParams p;
  p.every = 0.1;
  FrameWriter w(dir, p, 2);
  w.write(0, set_with(10, 6, 0));
  const std::string x = read_text(dir + "/frames.xdmf");
  EXPECT_NE(x.find("Grid Name=\"walls\""), std::string::npos);
  EXPECT_EQ(x.find("Grid Name=\"grains\""), std::string::npos);
  EXPECT_EQ(rows(dir + "/frame_00000.h5", "walls/pos"), 6u);
}

}  // namespace
}  // namespace sphdem
