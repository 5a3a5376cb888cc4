// Displacement volumes and deformation transfer (seed 9.3.3) on the bumpy plane over its flat base:
// encode time (normal displacements + the encoding's own set-up: JᵀJ pattern and symbolic factorisation
// for volumes, Poisson factorisation for transfer) and per-frame reconstruct time on a bend animated from
// 30° to 120° (the base's free part rolled onto a circular arc, the handle part moved rigidly: the bend120
// scene's handle transform). Normal displacements per frame as a reference.
// Usage: bench_encodings [resolution ...] [--volumes-max=N]   (default: 100k 1M, volumes up to 200k:
// each volume frame is a few sparse factorisations of a #V×#V matrix, too slow to animate at 1M)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "core/scenes.h"
#include "core/solver.h"
#include "detail/deformation_transfer.h"
#include "detail/displacement_volumes.h"
#include "detail/normal_displacements.h"

using namespace msd::bench;

namespace {

constexpr double kPi = 3.14159265358979323846;

// The flat plane z = 0 rolled up onto an arc from x = 0.2 over the free length 0.6 by `degrees`; x > 0.8
// continues along the end tangent (the bend scenes' handle transform).
msd::Positions bend(const msd::Positions& flat, double degrees) {
  const double theta = degrees * kPi / 180, R = 0.6 / theta, x0 = 0.2;
  msd::Positions out(flat.rows(), 3);
  for (Eigen::Index i = 0; i < flat.rows(); ++i) {
    const double s = flat(i, 0) - x0, phi = std::clamp(s / R, 0.0, theta);
    msd::Vec3 p(s < 0 ? flat(i, 0) : x0 + R * std::sin(phi), flat(i, 1), R * (1 - std::cos(phi)));
    if (s > R * theta) p += (s - R * theta) * msd::Vec3(std::cos(theta), 0, std::sin(theta));
    out.row(i) = p.transpose();
  }
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> sizes;
  long volumes_max = 200000;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--volumes-max=", 0) == 0)
      volumes_max = msd::parse_resolution(arg.substr(14));
    else
      sizes.push_back(arg);
  }
  if (sizes.empty()) sizes = {"100k", "1M"};
  std::printf("sparse solver: %s, %d frames of transfer and normal, 3 of volumes\n",
              msd::SparseSPDSolver::backend().c_str(), 10);
  std::printf("%9s | %10s %13s %13s | %10s %13s %5s %6s %10s %10s | %13s\n", "vertices", "transfer",
              "frame med", "frame min", "volumes", "frame med", "iters", "facts", "max err", "rms err",
              "normal frame");
  std::printf("%9s | %10s %13s %13s | %10s %13s %5s %6s %10s %10s | %13s\n", "", "encode[s]", "[ms]", "[ms]",
              "encode[s]", "[ms]", "", "", "(prism)", "(prism)", "med [ms]");
  for (const auto& size : sizes) {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(size);
    const msd::Scene scene = msd::make_surface(msd::SceneShape::Plane, options);
    const long nv = static_cast<long>(scene.P.rows());
    std::vector<msd::Positions> bases;
    for (double degrees : {30.0, 60.0, 90.0, 120.0}) bases.push_back(bend(scene.smooth, degrees));
    msd::Positions out(nv, 3);

    msd::DeformationTransfer transfer;
    transfer.set_anchor_vertices(scene.region.constrained_vertices());
    auto t0 = Clock::now();
    transfer.encode(scene.P, scene.F, scene.smooth, scene.F);
    const double transfer_encode = seconds_since(t0);
    std::vector<double> transfer_frames;
    for (int f = 0; f < 10; ++f) {
      t0 = Clock::now();
      transfer.reconstruct(bases[f % bases.size()], out);
      transfer_frames.push_back(1000 * seconds_since(t0));
    }

    const msd::NormalDisplacements& nd_const = transfer.normal_displacements();
    msd::NormalDisplacements nd = nd_const;  // a copy: reconstruct() is not const
    std::vector<double> normal_frames;
    for (int f = 0; f < 10; ++f) {
      t0 = Clock::now();
      nd.reconstruct(bases[f % bases.size()], out);
      normal_frames.push_back(1000 * seconds_since(t0));
    }

    char volumes_text[160];
    if (nv <= volumes_max) {
      msd::DisplacementVolumes volumes;
      t0 = Clock::now();
      volumes.encode(scene.P, scene.F, scene.smooth, scene.F);
      const double volumes_encode = seconds_since(t0);
      std::vector<double> volume_frames;
      int iterations = 0, factorizations = 0;
      double max_error = 0, rms_error = 0;
      for (int f = 1; f < 4; ++f) {  // 60°, 90°, 120°
        volumes.reconstruct(bases[f], out);
        const auto& r = volumes.report();
        volume_frames.push_back(1000 * r.seconds);
        iterations = std::max(iterations, r.iterations);
        factorizations = std::max(factorizations, r.factorizations);
        max_error = std::max(max_error, r.max_relative_error);
        rms_error = std::max(rms_error, r.rms_relative_error);
      }
      std::snprintf(volumes_text, sizeof volumes_text, "%10.2f %13.1f %5d %6d %10.2g %10.2g", volumes_encode,
                    median(volume_frames), iterations, factorizations, max_error, rms_error);
    } else {
      std::snprintf(volumes_text, sizeof volumes_text, "%10s %13s %5s %6s %10s %10s", "skipped", "(>max)", "",
                    "", "", "");
    }
    std::printf("%9ld | %10.2f %13.1f %13.1f | %s | %13.1f\n", nv, transfer_encode, median(transfer_frames),
                *std::min_element(transfer_frames.begin(), transfer_frames.end()), volumes_text,
                median(normal_frames));
    std::fflush(stdout);
  }
  return 0;
}
