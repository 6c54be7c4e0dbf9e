// ParaView frames: one parallel HDF5 file per frame (frame_NNNNN.h5) and one XDMF file
// (frames.xdmf) that indexes them all as a time series with a "fluid" block and, optionally, a
// "walls" block and (when the run has grains) a "grains" block of grain boundary particles. Open
// frames.xdmf in ParaView (Xdmf3 reader) to see the run.
#pragma once

#include <string>
#include <vector>

#include "scene/scene.hpp"
#include "solver/particles.hpp"

namespace sphdem {

class FrameWriter {
 public:
  FrameWriter(const std::string& dir, const FrameParams& params, int dim);
  // Writes one frame (collective). Rewrites the XDMF index so it is valid after every frame.
  void write(Real time, const ParticleSet<Host>& ps);
  int count() const { return int(frames_.size()); }
  // For restarts: frames already on disk are kept in the index.
  void adopt_existing(Real up_to_time);

 private:
  struct Frame {
    Real time;
    std::string file;
    Index n_fluid, n_wall, n_grain = 0;
  };
  void write_index() const;

  std::string dir_;
  FrameParams params_;
  int dim_;
  std::vector<Frame> frames_;
};

}  // namespace sphdem
