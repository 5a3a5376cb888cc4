#include "apps/msdeform/camera_options.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "apps/msdeform/commands.h"
#include "msdeform/core/atomic_file.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/mesh.h"

namespace msd::cli {

void CameraOptions::add_to(CLI::App& cmd) {
  auto* g = cmd.add_option_group("camera", "Pictures: which way is up, where the camera sits, what it frames");
  g->add_option("--up", up, "World axis drawn upwards: auto (away from the fixed vertices when they sit to one side, else from the principal axes: a flat shape is seen from "
                            "above, anything else stands along its longest axis), x, y, z, -x, -y or -z")
      ->capture_default_str();
  g->add_option("--view", view, "Camera direction: auto, or AZ,EL in degrees (azimuth about up from the front, "
                                "elevation above the horizon; auto is 31,34.4). With an explicit --up the front is "
                                "fixed (the camera at azimuth 0 sits on -y for z up, else on +z), so separate runs "
                                "draw a shape and its deformations from the same place")
      ->capture_default_str();
  g->add_option("--focus", focus, "Frame all of the shape, or its handles")
      ->check(CLI::IsMember({"all", "handle"}))
      ->capture_default_str();
}

void CameraOptions::apply(const Positions& P, const Region& region, RenderOptions& o) const {
  ViewAxes axes;
  if (up == "auto") {
    axes = edit_view_axes(P, region.num_vertices() > 0 ? region.fixed_vertices() : std::vector<int>());
  } else {
    const bool negative = !up.empty() && up[0] == '-';
    const std::string axis = negative ? up.substr(1) : up;
    if (axis != "x" && axis != "y" && axis != "z")
      throw InvalidInput("--up " + up + ": expected auto, x, y, z, -x, -y or -z");
    axes = view_axes(P, (negative ? -1.0 : 1.0) * Vec3::Unit(axis[0] - 'x'));
  }
  o.up = axes.up;
  if (view == "auto") {
    o.view_direction = axes.default_direction();
  } else {
    const size_t comma = view.find(',');
    const std::optional<double> az = cli::decimal_number(view.substr(0, comma)),
                                el = comma == std::string::npos ? std::nullopt : cli::decimal_number(view.substr(comma + 1));
    if (!az || !el || std::abs(*el) >= 90)
      throw InvalidInput("--view " + view + ": expected auto or AZ,EL in degrees with |EL| < 90");
    if (up != "auto") {
      // Up and view both given: the front is a fixed world axis, not one found from the shape's extents, so
      // separate runs (a rest shape, its deformations) take their pictures from the same place.
      axes.front = axes.up.z() != 0 ? Vec3(Vec3::UnitY()) : Vec3(-Vec3::UnitZ());
      axes.side = axes.front.cross(axes.up);
    }
    o.view_direction = axes.direction(*az, *el);
  }
  if (focus == "handle") {
    if (region.num_handles() == 0) throw InvalidInput("--focus handle: the region has no handle");
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    for (int v = 0; v < region.num_vertices(); ++v)
      if (region.handle_of(v) >= 0) lo = lo.cwiseMin(P.row(v).transpose()), hi = hi.cwiseMax(P.row(v).transpose());
    const Vec3 centre = (lo + hi) / 2;
    double enclosing = 0;  // the handles' sphere about centre, and the shape's about its box centre
    for (int v = 0; v < region.num_vertices(); ++v)
      if (region.handle_of(v) >= 0) enclosing = std::max(enclosing, (P.row(v).transpose() - centre).norm());
    const Vec3 shape_centre = bounding_box_centre(P);
    const double shape = (P.rowwise() - shape_centre.transpose()).rowwise().norm().maxCoeff();
    // The handles and a quarter of their size around them; never a zero sphere (one handle vertex).
    const double radius = std::max(1.25 * enclosing, 0.05 * bounding_box_diagonal(P));
    if (radius < 0.6 * shape) {  // else the handles span most of the shape: frame all of it, tightly
      o.framing = Framing::BoundingSphere;
      o.sphere_center = centre;
      o.sphere_radius = radius;
    }
  }
}

void check_picture_output(const std::string& path, const char* option) {
  if (file_extension(path) != ".png") throw InvalidInput(std::string(option) + " " + path + ": the picture is a .png");
  check_writable(path, option);
}

}  // namespace msd::cli
