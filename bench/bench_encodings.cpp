// Displacement volumes and deformation transfer (seed 9.3.3) on the bumpy plane over its flat base:
// encode time (normal displacements + the encoding's own set-up: dual-cell volumes and bounds for
// volumes, Poisson factorisation for transfer) and per-frame reconstruct time on a bend animated from
// 30° to 120° (the base's free part rolled onto a circular arc, the handle part moved rigidly: the bend120
// scene's handle transform). Normal displacements per frame as a reference. Volumes: every frame of the
// animation 30° → 120° in steps of 7.5° (warm-started, as in an interactive session; the first frame
// cold), then the 120° frame from a cold start; sweeps are Jacobi sweeps, errors per dual cell.
// Usage: bench_encodings [resolution ...] [--volumes-max=N]   (default: 100k 1M, volumes up to 1M)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/scenes.h"
#include "msdeform/core/solver.h"
#include "msdeform/detail/deformation_transfer.h"
#include "msdeform/detail/displacement_volumes.h"
#include "msdeform/detail/normal_displacements.h"

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

// CPU time of the process (all threads) in seconds: the cost of a frame independent of how busy the
// machine is (wall time on a loaded machine can be several times the quiet figure).
double process_seconds() {
  timespec t;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> sizes;
  long volumes_max = 1000000;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--volumes-max=", 0) == 0)
      volumes_max = msd::parse_resolution(arg.substr(14));
    else
      sizes.push_back(arg);
  }
  if (sizes.empty()) sizes = {"100k", "1M"};
  std::printf("sparse solver: %s, 10 frames of transfer and normal, 13 + 1 of volumes\n",
              msd::SparseSPDSolver::backend().c_str());
  std::printf("%9s | %10s %10s %10s | %10s %10s %10s %10s %6s %10s %10s %6s %9s | %10s\n", "vertices",
              "transfer", "frame med", "frame min", "volumes", "frame med", "cpu/frame", "frame max",
              "sweeps", "max err", "cold 120", "sweeps", "max err", "normal");
  std::printf("%9s | %10s %10s %10s | %10s %10s %10s %10s %6s %10s %10s %6s %9s | %10s\n", "", "encode[s]",
              "[ms]", "[ms]", "encode[s]", "warm [ms]", "[ms]", "[ms]", "(max)", "(cell)", "[ms]", "",
              "(cell)", "med [ms]");
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

    msd::NormalDisplacements nd;  // every vertex (transfer's own places only its constrained vertices)
    nd.encode(scene.P, scene.F, scene.smooth, scene.F);
    std::vector<double> normal_frames;
    for (int f = 0; f < 10; ++f) {
      t0 = Clock::now();
      nd.reconstruct(bases[f % bases.size()], out);
      normal_frames.push_back(1000 * seconds_since(t0));
    }

    char volumes_text[200];
    if (nv <= volumes_max) {
      msd::DisplacementVolumes volumes;
      t0 = Clock::now();
      volumes.encode(scene.P, scene.F, scene.smooth, scene.F);
      const double volumes_encode = seconds_since(t0);
      std::vector<msd::Positions> animation;
      for (int k = 0; k <= 12; ++k) animation.push_back(bend(scene.smooth, 30 + 7.5 * k));
      std::vector<double> volume_frames;
      int sweeps = 0;
      double max_error = 0;
      const double cpu0 = process_seconds();
      for (const auto& base : animation) {
        volumes.reconstruct(base, out);
        const auto& r = volumes.report();
        volume_frames.push_back(1000 * r.seconds);
        sweeps = std::max(sweeps, r.iterations);
        max_error = std::max(max_error, r.max_relative_error);
      }
      const double cpu_per_frame = 1000 * (process_seconds() - cpu0) / animation.size();
      msd::DisplacementVolumeOptions cold_options;
      cold_options.warm_start = false;
      msd::DisplacementVolumes cold(cold_options);
      cold.encode(scene.P, scene.F, scene.smooth, scene.F);
      cold.reconstruct(animation.back(), out);
      const auto& c = cold.report();
      std::snprintf(volumes_text, sizeof volumes_text,
                    "%10.2f %10.1f %10.1f %10.1f %6d %10.2g %10.1f %6d %9.2g", volumes_encode,
                    median(volume_frames), cpu_per_frame,
                    *std::max_element(volume_frames.begin(), volume_frames.end()), sweeps, max_error,
                    1000 * c.seconds, c.iterations, c.max_relative_error);
    } else {
      std::snprintf(volumes_text, sizeof volumes_text, "%10s %10s %10s %6s %10s %10s %6s %9s", "skipped",
                    "(>max)", "", "", "", "", "", "");
    }
    std::printf("%9ld | %10.2f %10.1f %10.1f | %s | %10.1f\n", nv, transfer_encode, median(transfer_frames),
                *std::min_element(transfer_frames.begin(), transfer_frames.end()), volumes_text,
                median(normal_frames));
    std::fflush(stdout);
  }
  return 0;
}
