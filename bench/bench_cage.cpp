// Cage-based free-form deformation (seed 9.5.2) on the bumpy bar (bar-bend120) with the generated 26-DOP
// cage: mean value coordinates per point and cage vertex, the harmonic coordinates' grid solve, and on the
// deformer an affine frame (precomputed affine basis, one handle) and a cage-vertex edit (deform_controls,
// with and without the basis cache) per second.
// Usage: bench_cage [coordinate-size [frame-size]]   (default: 100k 1M)
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench_common.h"
#include "msdeform/core/memory.h"
#include "msdeform/core/parallel.h"
#include "msdeform/core/scenes.h"
#include "msdeform/deformation/cage.h"

using namespace msd::bench;

int main(int argc, char** argv) {
  msd::retain_freed_memory();
  const std::vector<std::string> sizes = msd::bench::sizes(argc, argv, {"100k", "1M"});
  const std::string coord_size = sizes[0], frame_size = sizes.size() > 1 ? sizes[1] : sizes[0];

  // Coordinates alone.
  {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(coord_size);
    const msd::Scene scene = msd::make_scene("bar-bend120", options);
    msd::Positions C;
    msd::Faces F;
    auto t0 = Clock::now();
    msd::offset_kdop_cage(scene.P, 0.05, 1, C, F);
    const double cage_ms = ms_since(t0);
    const msd::MeanValueCage cage(C, F);
    const long n = scene.P.rows();
    const int m = cage.num_vertices();
    std::printf(
        "26-DOP cage (1 subdivision) around %ld points: %d vertices, %d faces, %d edges, built in %.2f ms\n",
        n, m, cage.num_faces(), cage.num_edges(), cage_ms);
    std::vector<double> sink(2, 0.0);
    const auto serial = time_frames(3, [&](int) {
      msd::MeanValueWorkspace ws;
      std::vector<double> w(m);
      const long count = std::min<long>(n, 20000);
      for (long i = 0; i < count; ++i) {
        cage.coordinates(scene.P.row(i), ws, w.data());
        sink[0] += w[0];
      }
    });
    const double serial_us = 1e3 * serial.front() / std::min<long>(n, 20000);
    const auto parallel = time_frames(3, [&](int) {
      msd::parallel_for_chunks(
          n,
          [&](long begin, long end) {
            msd::MeanValueWorkspace ws;
            std::vector<double> w(m);
            for (long i = begin; i < end; ++i) cage.coordinates(scene.P.row(i), ws, w.data());
          },
          256);
    });
    std::printf("%-34s %12s %14s %16s\n", "mean value coordinates", "us/point", "ns/(pt*vertex)",
                "points/s (all)");
    std::printf("%-34s %12.2f %14.1f %16s\n", "  one thread", serial_us, 1e3 * serial_us / m, "");
    std::printf("%-34s %12.2f %14.1f %16.3g\n", "  parallel_for_chunks", 1e3 * parallel.front() / n,
                1e6 * parallel.front() / (double(n) * m), n / (1e-3 * parallel.front()));
    for (const int resolution : {32, 64}) {
      t0 = Clock::now();
      const msd::HarmonicCoordinates hc(C, F, resolution);
      const double build = seconds_since(t0);
      const Eigen::Vector3i g = hc.grid_size();
      const auto eval = time_frames(3, [&](int) {
        msd::parallel_for_chunks(
            n,
            [&](long begin, long end) {
              std::vector<double> w(m);
              for (long i = begin; i < end; ++i) hc.coordinates(scene.P.row(i), w.data());
            },
            1024);
      });
      std::printf(
          "harmonic coordinates, %3d cells: grid %dx%dx%d, %d inside + %d near-boundary nodes, precompute "
          "%.2f s, "
          "%.2f us/point to interpolate\n",
          resolution, g[0], g[1], g[2], hc.num_inside_nodes(), hc.num_boundary_nodes(), build,
          1e3 * eval.front() / n);
    }
    if (sink[0] == 12345.678) std::printf(" ");
  }

  // The deformer.
  {
    msd::SceneOptions options;
    options.resolution = msd::parse_resolution(frame_size);
    const msd::Scene scene = msd::make_scene("bar-bend120", options);
    const long n = scene.P.rows();
    msd::CageDeformer d;
    d.set_basis_cache_bytes(size_t(4) << 30);
    auto t0 = Clock::now();
    d.prepare(scene.P, scene.F, scene.region);
    const double prepare = seconds_since(t0);
    std::printf(
        "\ncage-mvc on %ld points, %ld cage vertices: prepare %.2f s (basis at every point, cached)\n", n,
        long(d.num_coefficients()), prepare);
    msd::Positions out(n, 3);
    std::vector<msd::Mat4> T = scene.transforms;
    const msd::Mat4 full = T[0];
    const auto frames = time_frames(20, [&](int f) {
      const double a = (f + 1) / 20.0;
      T[0] = (1 - a) * msd::Mat4::Identity() + a * full;
      d.deform(T, out);
    });
    std::printf("%-40s %14s %14s %14s\n", "frame", "median[ms]", "min[ms]", "points/s");
    std::printf("%-40s %14.2f %14.2f %14.3g\n", "affine (one handle)", frames[frames.size() / 2],
                frames.front(), n / (1e-3 * frames[frames.size() / 2]));
    Eigen::MatrixX3d moves = Eigen::MatrixX3d::Zero(d.num_coefficients(), 3);
    const auto edits = time_frames(5, [&](int f) {
      moves(f % moves.rows(), 2) += 0.01;
      d.deform_controls(moves, out);
    });
    std::printf("%-40s %14.2f %14.2f %14.3g\n", "deform_controls (cached basis)", edits[edits.size() / 2],
                edits.front(), n / (1e-3 * edits[edits.size() / 2]));
    // Without the cache (the default 256 MB holds it only below ~100k points here) every edit
    // re-evaluates the coordinates at every point.
    msd::CageDeformer uncached;
    uncached.prepare(scene.P, scene.F, scene.region);
    const auto slow = time_frames(1, [&](int) { uncached.deform_controls(moves, out); });
    std::printf("%-40s %14.2f %14.2f %14.3g\n", "deform_controls (256 MB: not cached)", slow.front(),
                slow.front(), n / (1e-3 * slow.front()));
  }
  return 0;
}
