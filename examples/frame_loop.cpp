// An interactive loop without a window: prepare a method once, then run one frame per handle position, as
// a viewer does while the user drags. Each frame is checked (finite, handle met, warnings) and timed.
//   frame_loop [METHOD [FRAMES]]   (default: multiscale-normal, 24 frames, on the built-in bumpy plane)
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include <msdeform/core/scenes.h>
#include <msdeform/core/version.h>
#include <msdeform/reconstruction/catalogue.h>

int main(int argc, char** argv) try {
  const std::string method = argc > 1 ? argv[1] : "multiscale-normal";
  const int frames = argc > 2 ? std::stoi(argv[2]) : 24;
  std::printf("frame_loop: msdeform %s (headers %s)\n", msd::version(), MSD_VERSION_STRING);

  msd::SceneOptions options;
  options.resolution = 10000;
  const msd::Scene scene = msd::make_surface(msd::SceneShape::Plane, options);  // fixed x < 0.2, handle x > 0.8

  using Clock = std::chrono::steady_clock;
  auto start = Clock::now();
  auto deformer = msd::builtin_methods().make(method);
  deformer->prepare(scene.P, scene.F, scene.region);
  std::printf("frame_loop: %s prepared %d vertices in %.2f s\n", method.c_str(), deformer->num_vertices(),
              std::chrono::duration<double>(Clock::now() - start).count());

  const std::vector<int> handle = scene.region.handle_vertices(0);
  msd::Vec3 centroid = msd::Vec3::Zero();
  for (int v : handle) centroid += scene.P.row(v).transpose() / static_cast<double>(handle.size());
  msd::Positions out;  // sized by the first frame, reused by the others
  double slowest = 0;
  for (int frame = 1; frame <= frames; ++frame) {
    // The handle rises by up to 0.3 and turns about its centroid by up to 30 degrees around y.
    const double t = static_cast<double>(frame) / frames;
    const msd::Mat3 R = Eigen::AngleAxisd(-t * M_PI / 6, msd::Vec3::UnitY()).toRotationMatrix();
    msd::Mat4 T = msd::Mat4::Identity();
    T.topLeftCorner<3, 3>() = R;
    T.topRightCorner<3, 1>() = centroid + msd::Vec3(0, 0, 0.3 * t) - R * centroid;

    start = Clock::now();
    deformer->deform({T}, out);  // checks every coordinate is finite, fills the frame report
    slowest = std::max(slowest, std::chrono::duration<double, std::milli>(Clock::now() - start).count());

    double error = 0;
    for (int v : handle) error = std::max(error, (msd::Vec3(out.row(v)) - msd::transform_point(T, scene.P.row(v))).norm());
    const msd::FrameReport& report = deformer->frame_report();
    for (const std::string& warning : report.warnings) std::printf("frame %d: warning: %s\n", frame, warning.c_str());
    const double allowed = deformer->traits().exact_constraints ? 1e-8 : 0.05;  // the unit square's scale
    if (error > allowed) {
      std::fprintf(stderr, "frame_loop: frame %d missed the handle by %g\n", frame, error);
      return 1;
    }
  }
  std::printf("frame_loop: %d frames, slowest %.2f ms, last folded faces %d\n", frames, slowest,
              deformer->frame_report().folded_faces);
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "frame_loop: %s\n", e.what());
  return 1;
}
