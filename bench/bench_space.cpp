// Space deformations (seed 9.5.1 lattice FFD, 9.6 triharmonic RBF): prepare time, affine frames with the
// precomputed per-point basis (points per second), control-point frames, and the RBF's factorisation
// and basis precompute for 1k and 10k centres.
// Usage: bench_space [resolution ...]   (default: 1M)
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/lattice.h"
#include "msdeform/deformation/rbf.h"

using namespace msd;
using namespace msd::bench;

namespace {

// Sorted milliseconds of 21 affine frames (out sized by a first frame).
std::vector<double> frame_ms(Deformer& d, const std::vector<Mat4>& transforms) {
  Positions out;
  d.deform(transforms, out);
  return time_frames(21, [&](int) { d.deform(transforms, out); });
}

}  // namespace

int main(int argc, char** argv) {
  std::printf("Affine frames use the precomputed per-point affine basis (12 multiply-adds per point and handle).\n");
  std::printf("%-8s %9s %9s %11s %16s %16s %14s\n", "method", "points", "basis", "prepare[s]", "frame med/min[ms]",
              "Mpoints/s med/max", "controls[ms]");
  for (const std::string& size : sizes(argc, argv, {"1M"})) {
    SceneOptions o;
    o.resolution = parse_resolution(size);
    const Scene s = make_scene("lift", o);
    for (int method = 0; method < 2; ++method) {
      std::unique_ptr<SpaceDeformer> d;
      if (method == 0) d = std::make_unique<LatticeDeformer>();
      else d = std::make_unique<RbfDeformer>(RbfOptions{1000});
      auto t0 = Clock::now();
      d->prepare(s.P, s.F, s.region);
      const double prepare = seconds_since(t0);
      const std::vector<double> frame = frame_ms(*d, s.transforms);
      double controls = -1;
      if (d->has_control_points()) {
        Positions out;
        Eigen::MatrixX3d dc = Eigen::MatrixX3d::Zero(d->num_coefficients(), 3);
        dc(dc.rows() / 2, 2) = 0.01;
        controls = time_frames(5, [&](int) { d->deform_controls(dc, out); })[2];
      }
      std::printf("%-8s %9ld %9d %11.2f %8.2f/%-7.2f %8.0f/%-7.0f %14.1f\n", d->name().c_str(), long(s.P.rows()),
                  d->num_coefficients(), prepare, frame[10], frame[0], s.P.rows() / frame[10] / 1e3,
                  s.P.rows() / frame[0] / 1e3, controls);
      std::fflush(stdout);
    }
  }
  // The RBF's dense system for n centres: factorisation plus the affine basis of one handle (4 solves),
  // on n random points that are all constrained (half fixed, half one handle).
  std::printf("\nRBF factorisation and affine basis for n centres (n random points, all constrained)\n");
  std::printf("%8s %11s\n", "centres", "prepare[s]");
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int n : {1000, 10000}) {
    Positions P(n, 3);
    for (int i = 0; i < n; ++i) P.row(i) << u(rng), u(rng), u(rng);
    std::vector<int> codes(n);
    for (int i = 0; i < n; ++i) codes[i] = P(i, 0) < 0.5 ? Region::kFixed : Region::kFirstHandle;
    RbfDeformer rbf(RbfOptions{n});
    const auto t0 = Clock::now();
    rbf.prepare(P, Faces(0, 3), Region::from_codes(codes));
    std::printf("%8ld %11.2f\n", long(rbf.centres().rows()), seconds_since(t0));
    std::fflush(stdout);
  }
  return 0;
}
