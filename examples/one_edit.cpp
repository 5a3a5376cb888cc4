// The smallest msdeform program: load a mesh, build a region from spheres, move one handle, deform, save.
//   one_edit [MESH [OUT]]   (without MESH it first writes the built-in bumpy plane to bumpy_plane.off)
#include <cstdio>
#include <exception>

#include <msdeform/core/errors.h>
#include <msdeform/core/mesh_io.h>
#include <msdeform/core/region.h>
#include <msdeform/core/scenes.h>
#include <msdeform/reconstruction/catalogue.h>

int main(int argc, char** argv) try {
  std::string input = argc > 1 ? argv[1] : "bumpy_plane.off";
  const std::string output = argc > 2 ? argv[2] : "one_edit_out.off";
  if (argc <= 1) {
    const msd::Scene scene = msd::make_surface(msd::SceneShape::Plane);
    msd::save_mesh(scene.P, scene.F, input);
  }

  // Load: #V×3 positions and #F×3 triangles, the file's vertices in the file's order.
  const msd::TriangleSoup mesh = msd::load_soup(input);
  const msd::Positions& P = mesh.P;
  const double diagonal = (P.colwise().maxCoeff() - P.colwise().minCoeff()).norm();

  // Region: the handle is a sphere around the vertex farthest along x; everything beyond a larger sphere
  // is fixed; the shell between is free to deform.
  Eigen::Index tip;
  P.col(0).maxCoeff(&tip);
  const msd::Vec3 center = P.row(tip).transpose();
  msd::Region region(static_cast<int>(P.rows()), msd::Region::kFixed);
  region.set_free(msd::select_sphere(P, center, 0.6 * diagonal));
  region.set_handle(msd::select_sphere(P, center, 0.15 * diagonal), 0);

  // One handle, lifted by a tenth of the diagonal.
  msd::Mat4 lift = msd::Mat4::Identity();
  lift(2, 3) = 0.1 * diagonal;

  auto shell = msd::builtin_methods().make("shell");
  shell->prepare(P, mesh.F, region);
  const msd::Positions deformed = shell->deform({lift});

  // Check before saving: the handle reached its target.
  double error = 0;
  for (int v : region.handle_vertices(0))
    error = std::max(error, (msd::Vec3(deformed.row(v)) - msd::transform_point(lift, P.row(v))).norm());
  for (const std::string& warning : shell->frame_report().warnings) std::fprintf(stderr, "warning: %s\n", warning.c_str());
  if (error > 1e-8 * diagonal) {
    std::fprintf(stderr, "one_edit: the handle missed its target by %g\n", error);
    return 1;
  }
  msd::save_mesh(deformed, mesh.F, output);
  std::printf("one_edit: %d vertices, handle of %zu vertices met to %.1e; wrote %s\n", static_cast<int>(P.rows()),
              region.handle_vertices(0).size(), error, output.c_str());
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "one_edit: %s\n", e.what());
  return 1;
}
