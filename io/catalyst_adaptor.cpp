// The ParaView 5.11 legacy Catalyst adaptor (io/insitu.hpp): a vtkCPProcessor with one
// vtkCPPythonScriptV2Pipeline per script. Compiled only with -DSPHDEM_ENABLE_CATALYST=ON.
#include <vtkAOSDataArrayTemplate.h>
#include <vtkCPDataDescription.h>
#include <vtkCPInputDataDescription.h>
#include <vtkCPProcessor.h>
#include <vtkCPPythonScriptV2Pipeline.h>
#include <vtkDoubleArray.h>
#include <vtkFieldData.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/insitu.hpp"

namespace sphdem {

namespace {

using RealArray = vtkAOSDataArrayTemplate<Real>;
static_assert(sizeof(Vec3) == 3 * sizeof(Real), "Vec3 must be three packed Reals (zero copy)");

// A VTK array over `n` values of `comps` Reals at `data`, without a copy: the solver's host
// particles outlive the call (VTK keeps the pointer only during CoProcess; the producers are
// given new data on every extract step).
vtkSmartPointer<RealArray> view(const char* name, const Real* data, Index n, int comps) {
  auto a = vtkSmartPointer<RealArray>::New();
  a->SetName(name);
  a->SetNumberOfComponents(comps);
  a->SetArray(const_cast<Real*>(data), vtkIdType(n) * comps, /*save=*/1);
  return a;
}

vtkSmartPointer<RealArray> scalar(const char* name, Real v) {
  auto a = vtkSmartPointer<RealArray>::New();
  a->SetName(name);
  a->InsertNextValue(v);
  return a;
}

// Points [begin, begin + n) of `ps` with the named fields.
vtkSmartPointer<vtkPolyData> points(const ParticleSet<Host>& ps, Index begin, Index n) {
  auto pd = vtkSmartPointer<vtkPolyData>::New();
  vtkNew<vtkPoints> pts;
  pts->SetData(view("pos", &ps.pos[std::size_t(begin)].x, n, 3));
  pd->SetPoints(pts);
  vtkPointData* d = pd->GetPointData();
  d->AddArray(view("vel", &ps.vel[std::size_t(begin)].x, n, 3));
  d->AddArray(view("rho", &ps.rho[std::size_t(begin)], n, 1));
  d->AddArray(view("press", &ps.press[std::size_t(begin)], n, 1));
  vtkNew<vtkAOSDataArrayTemplate<GlobalId>> id;
  id->SetName("id");
  id->SetArray(const_cast<GlobalId*>(&ps.id[std::size_t(begin)]), vtkIdType(n), 1);
  d->AddArray(id);
  return pd;
}

class CatalystAdaptor final : public InSituAdaptor {
 public:
  CatalystAdaptor(const Scene& scene, const std::string& out_dir)
      : scene_(scene), dir_(out_dir + "/catalyst") {
    std::error_code ec;
    std::filesystem::create_directories(dir_, ec);
    if (ec) throw InputError("insitu: cannot create '" + dir_ + "': " + ec.message());
    processor_ = vtkSmartPointer<vtkCPProcessor>::New();
    // Extracts are written relative to this folder.
    if (!processor_->Initialize(dir_.c_str()))
      throw InputError("insitu: Catalyst (vtkCPProcessor) failed to initialise");
    for (const std::string& s : scene.insitu.scripts) {
      vtkNew<vtkCPPythonScriptV2Pipeline> pipeline;
      // Absolute: Catalyst imports the script relative to its working folder (dir_).
      const std::string path = std::filesystem::absolute(s).string();
      if (!pipeline->Initialize(path.c_str())) {
        throw InputError(scene.source + ": insitu.scripts: Catalyst could not load '" + s +
                         "' (see the Python error above)");
      }
      processor_->AddPipeline(pipeline);
    }
    names_->SetName("solid_names");
    for (const Solid& s : scene.solids) names_->InsertNextValue(s.name);
  }

  ~CatalystAdaptor() override {
    // Before MPI_Finalize: run_scene owns the adaptor.
    processor_->Finalize();
    processor_ = nullptr;
    if (std::FILE* f = std::fopen((dir_ + "/timing.json").c_str(), "w")) {
      // The first extract step also starts ParaView's Python and imports the scripts.
      const double rest = seconds_ - first_seconds_;
      std::fprintf(f,
                   "{\"extract_steps\": %lld, \"seconds\": %.6f, \"first_ms\": %.3f, "
                   "\"ms_per_extract_step_after_first\": %.3f}\n",
                   static_cast<long long>(executed_), seconds_, 1e3 * first_seconds_,
                   executed_ > 1 ? 1e3 * rest / double(executed_ - 1) : 0.0);
      std::fclose(f);
    }
  }

  bool due(std::int64_t step) const override { return step % scene_.insitu.every_steps == 0; }

  void execute(std::int64_t step, Real time, const ParticleSet<Host>& ps, const StepParams& p,
               const std::vector<Vec3>& grain_force) override {
    if (grain_force.size() != scene_.solids.size())
      throw std::logic_error("insitu: grain_force has " + std::to_string(grain_force.size()) +
                             " entries for " + std::to_string(scene_.solids.size()) + " solids");
    const auto t0 = std::chrono::steady_clock::now();
    vtkNew<vtkCPDataDescription> dd;
    dd->AddInput("fluid");
    dd->AddInput("walls");
    dd->SetTimeData(double(time), vtkIdType(step));
    if (processor_->RequestDataDescription(dd)) {
      auto meta = [&](vtkPolyData* pd) {
        vtkFieldData* fd = pd->GetFieldData();
        fd->AddArray(scalar("time", time));
        fd->AddArray(scalar("step", Real(step)));
        fd->AddArray(scalar("dp", p.dp));
        fd->AddArray(scalar("h", p.h));
        fd->AddArray(scalar("dim", Real(p.dim)));
        fd->AddArray(names_);
      };
      vtkCPInputDataDescription* in_fluid = dd->GetInputDescriptionByName("fluid");
      if (in_fluid->GetIfGridIsNecessary()) {
        auto pd = points(ps, 0, ps.n_fluid);
        meta(pd);
        in_fluid->SetGrid(pd);
      }
      vtkCPInputDataDescription* in_walls = dd->GetInputDescriptionByName("walls");
      if (in_walls->GetIfGridIsNecessary()) {
        const Index b = ps.wall_begin(), n = ps.size() - b;
        auto pd = points(ps, b, n);
        meta(pd);
        vtkPointData* d = pd->GetPointData();
        d->AddArray(view("normal", &ps.normal[std::size_t(b)].x, n, 3));
        auto force = vtkSmartPointer<RealArray>::New();  // the fluid's force on the particle
        force->SetName("force");
        force->SetNumberOfComponents(3);
        force->SetNumberOfTuples(n);
        vtkNew<vtkIntArray> body;
        body->SetName("body");
        body->SetNumberOfTuples(n);
        for (Index i = 0; i < n; ++i) {
          const Vec3 f = ps.acc[std::size_t(b + i)] * ps.mass[std::size_t(b + i)];
          force->SetTypedTuple(vtkIdType(i), &f.x);
          body->SetValue(vtkIdType(i), ps.body[std::size_t(b + i)]);
        }
        d->AddArray(force);
        d->AddArray(body);
        // The grains' contact load on each solid (field data: one tuple per solid).
        auto grains = vtkSmartPointer<RealArray>::New();
        grains->SetName("grain_force");
        grains->SetNumberOfComponents(3);
        grains->SetNumberOfTuples(vtkIdType(grain_force.size()));
        for (std::size_t s = 0; s < grain_force.size(); ++s)
          grains->SetTypedTuple(vtkIdType(s), &grain_force[s].x);
        pd->GetFieldData()->AddArray(grains);
        in_walls->SetGrid(pd);
      }
      if (!processor_->CoProcess(dd))
        throw std::runtime_error("insitu: a Catalyst script failed at step " +
                                 std::to_string(step) + " (see the Python error above)");
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (executed_++ == 0) first_seconds_ = s;
    seconds_ += s;
  }

  std::int64_t executed() const override { return executed_; }
  double seconds() const override { return seconds_; }
  std::string name() const override { return "catalyst"; }

 private:
  const Scene& scene_;
  std::string dir_;
  vtkSmartPointer<vtkCPProcessor> processor_;
  vtkNew<vtkStringArray> names_;
  std::int64_t executed_ = 0;
  double seconds_ = 0, first_seconds_ = 0;
};

}  // namespace

std::unique_ptr<InSituAdaptor> make_catalyst_adaptor(const Scene& scene,
                                                     const std::string& out_dir) {
  return std::make_unique<CatalystAdaptor>(scene, out_dir);
}

}  // namespace sphdem
