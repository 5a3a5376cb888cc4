// Normal displacements (seed 9.3.2) on the bumpy plane over its flat base: encode time (closest points,
// Newton search) and per-frame reconstruct time (B' vertex normals + interpolation) on an animated edit;
// also the BVH build and closest-point queries alone, and the vertex-normal share of a frame.
// Usage: bench_detail [resolution ...]   (default: 100k 1M)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/scenes.h"
#include "msdeform/detail/closest_point.h"
#include "msdeform/detail/normal_displacements.h"

using namespace msd::bench;


int main(int argc, char** argv) {
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"100k", "1M"});
  std::printf("%10s %10s %11s %10s %14s %14s %15s %9s\n", "vertices", "bvh[s]", "closest[s]", "encode[s]",
              "frame med[ms]", "frame min[ms]", "normals med[ms]", "fallback");
  for (const auto& size : sizes) {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(size);
    const msd::Scene scene = msd::make_surface(msd::SceneShape::Plane, options);
    // The closest-point part alone: BVH build, then one query per vertex of S.
    auto t0 = Clock::now();
    const msd::ClosestPointQuery query(scene.smooth, scene.F);
    const double build = ms_since(t0) / 1000;
    t0 = Clock::now();
    const auto closest = query.query_all(scene.P);
    const double queries = ms_since(t0) / 1000;

    msd::NormalDisplacements nd;
    t0 = Clock::now();
    nd.encode(scene.P, scene.F, scene.smooth, scene.F);
    const double encode = ms_since(t0) / 1000;

    msd::Positions out(scene.P.rows(), 3), base = scene.smooth;
    std::vector<double> frames;
    for (int f = 0; f < 60; ++f) {
      // An animated bend-like edit of the base: lift the right half along a parabola.
      const double s = (f + 1) / 60.0;
      for (Eigen::Index i = 0; i < base.rows(); ++i) {
        const double x = scene.smooth(i, 0);
        base(i, 2) = x > 0.5 ? s * 0.6 * (x - 0.5) * (x - 0.5) : 0.0;
      }
      t0 = Clock::now();
      nd.reconstruct(base, out);
      frames.push_back(ms_since(t0));
    }
    std::sort(frames.begin(), frames.end());
    // The share of a frame spent on B' vertex normals (core's VertexNormals), for the breakdown.
    const msd::VertexNormals normals(scene.F, static_cast<int>(base.rows()));
    msd::Positions N(base.rows(), 3);
    std::vector<double> normal_times;
    for (int f = 0; f < 20; ++f) {
      t0 = Clock::now();
      normals.compute(base, N);
      normal_times.push_back(ms_since(t0));
    }
    std::sort(normal_times.begin(), normal_times.end());
    std::printf("%10ld %10.2f %11.2f %10.2f %14.2f %14.2f %15.2f %9d\n", long(scene.P.rows()), build, queries,
                encode, frames[frames.size() / 2], frames.front(), normal_times[normal_times.size() / 2],
                nd.report().fallback);
    std::fflush(stdout);
    (void)closest;
  }
  return 0;
}
