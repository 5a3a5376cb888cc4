// Transformation propagation (seed 9.1) on the lift scene: prepare() time per field type and per-frame
// deform() time per blend mode.
// Usage: bench_propagation [resolution ...]   (default: 100k 1M)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/solver.h"
#include "msdeform/deformation/propagation.h"

using namespace msd::bench;

namespace {

const char* field_name(msd::PropagationField f) {
  switch (f) {
    case msd::PropagationField::Euclidean: return "euclidean";
    case msd::PropagationField::Geodesic: return "geodesic";
    case msd::PropagationField::Harmonic: return "harmonic";
  }
  return "?";
}

//! Median seconds of `frames` deform() calls into a pre-sized output.
double frame_seconds(msd::TransformationPropagation& prop, const std::vector<msd::Mat4>& transforms, int frames) {
  msd::Positions out;
  prop.deform(transforms, out);  // sizes out
  std::vector<double> times;
  for (int f = 0; f < frames; ++f) {
    const auto t0 = std::chrono::steady_clock::now();
    prop.deform(transforms, out);
    times.push_back(seconds_since(t0));
  }
  std::nth_element(times.begin(), times.begin() + frames / 2, times.end());
  return times[frames / 2];
}
}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"100k", "1M"});
  std::printf("backend: %s\n", msd::SparseSPDSolver::backend().c_str());
  std::printf("%10s %10s %10s %12s %14s %16s\n", "vertices", "free", "field", "prepare[s]", "frame Matrix[ms]",
              "frame Decomp.[ms]");
  for (const auto& size : sizes) {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(size);
    const msd::Scene lift = msd::make_scene("lift", options);
    const msd::Scene twist = msd::make_scene("twist135", options);  // a rotation, for the slerp path
    const msd::Mesh mesh = msd::make_mesh(lift.P, lift.F);
    for (msd::PropagationField field :
         {msd::PropagationField::Euclidean, msd::PropagationField::Geodesic, msd::PropagationField::Harmonic}) {
      double frame[2] = {0, 0}, prepare = 0;
      for (int b = 0; b < 2; ++b) {
        msd::PropagationOptions o;
        o.field = field;
        o.blend = b == 0 ? msd::PropagationBlend::Matrix : msd::PropagationBlend::Decomposed;
        msd::TransformationPropagation prop(o);
        const auto t0 = std::chrono::steady_clock::now();
        prop.prepare(mesh, lift.region);
        if (b == 0) prepare = seconds_since(t0);
        frame[b] = frame_seconds(prop, b == 0 ? lift.transforms : twist.transforms, 21);
        if (b == 0 && field != msd::PropagationField::Euclidean) break;  // frame cost does not depend on the field
      }
      std::printf("%10ld %10zu %10s %12.3f %14.3f", long(lift.P.rows()), lift.region.free_vertices().size(),
                  field_name(field), prepare, 1e3 * frame[0]);
      if (field == msd::PropagationField::Euclidean)
        std::printf(" %16.3f\n", 1e3 * frame[1]);
      else
        std::printf(" %16s\n", "-");
      std::fflush(stdout);
    }
  }
  return 0;
}
