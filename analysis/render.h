#pragma once
//! \file Off-screen pictures of meshes, triangle soups and point clouds: an Embree 3 ray tracer (no window,
//! no GPU) that writes PNG, a
//! perceptual colour map for per-vertex scalars with a legend, a built-in 5×7 bitmap font, and contact
//! sheets. Colours are RGB triples in [0, 1] (sRGB); images are 8-bit RGB.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "msdeform/core/region.h"
#include "msdeform/core/types.h"

namespace msd {

//! An 8-bit RGB image, rows from the top, pixels left to right: rgb[3 (y width + x) + c].
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;

  Image() = default;
  //! width × height pixels of one colour (components in [0, 1], clamped).
  Image(int width, int height, const Vec3& fill = Vec3::Zero());
  std::uint8_t* pixel(int x, int y) { return rgb.data() + 3 * (static_cast<size_t>(y) * width + x); }
  const std::uint8_t* pixel(int x, int y) const {
    return rgb.data() + 3 * (static_cast<size_t>(y) * width + x);
  }
  //! Sets pixel (x, y) to colour (in [0, 1], clamped); ignores coordinates outside the image.
  void set(int x, int y, const Vec3& colour);
};

//! How the camera distance (and aim) is chosen; the camera always sits on view_direction.
enum class Framing {
  //! As close as possible with every vertex inside the frame (5% margin), aimed so the mesh's picture
  //! is centred: the mesh spans the full width or the full height. Framing follows the mesh, so two
  //! meshes (or two deformations of one) are generally drawn at different scales.
  Tight,
  //! The bounding sphere (or RenderOptions::sphere_*) fits the view, aimed at its centre: the picture
  //! scale does not depend on the view direction, and renders given one sphere share one camera.
  BoundingSphere,
};

struct RenderOptions {
  int width = 800, height = 600;  //!< pixels, including the legend panel
  //! Direction from the mesh towards the camera (any length). The default looks down at a z-up surface
  //! from the front left.
  Vec3 view_direction = Vec3(-0.6, -1.0, 0.8);
  //! World direction that appears upwards in the image (if parallel to view_direction, another axis is used).
  Vec3 up = Vec3(0, 0, 1);
  double fov_degrees = 35;  //!< full vertical field of view
  Framing framing = Framing::Tight;
  //! With Framing::BoundingSphere: the sphere to frame (world coordinates). A radius of 0 frames the
  //! mesh's own sphere (centre of the bounding box, radius to the farthest vertex). Pass one sphere to
  //! several renders, e.g. the results of different methods, to draw them at one scale and position.
  Vec3 sphere_center = Vec3::Zero();
  double sphere_radius = 0;
  int samples_per_axis = 2;  //!< supersampling: samples_per_axis² rays per pixel on a regular grid
  //! Point clouds (no faces): the radius of the sphere drawn at each point, in scene units; 0 chooses
  //! default_point_radius(P). Pass one radius to several renders (e.g. the rest cloud's) to draw them alike.
  double point_radius = 0;
  //! #V values to colour the surface with (viridis, interpolated at the hit point; one colour per sphere
  //! of a point cloud); null for base_color.
  const Eigen::VectorXd* vertex_scalar = nullptr;
  //! #V by 3 sRGB colours in [0, 1], interpolated over the faces, when there is no vertex_scalar (e.g. the
  //! roles of a region: fixed, free, each handle); null for base_color.
  const Positions* vertex_colors = nullptr;
  //! Faces (rows of F) drawn in highlight_color over any other colouring, e.g. self-intersecting ones.
  const std::vector<int>* highlighted_faces = nullptr;
  Vec3 highlight_color = Vec3(0.90, 0.05, 0.05);
  std::string scalar_label;  //!< title of the legend
  //! Colour-map range; when equal, robust_scalar_range(*vertex_scalar) is used.
  double scalar_min = 0, scalar_max = 0;
  Vec3 base_color = Vec3(0.80, 0.68, 0.54);  //!< surface colour without a scalar (warm clay)
  bool legend = true;                        //!< draw a colour bar with the range (only with a scalar)
  bool shadows = true;                       //!< the key light casts shadows
  //! Background: row y has colour (1 − t) top + t bottom, t = y / (height − 1) (the exact pixel value
  //! wherever no sample hit the mesh).
  Vec3 background_top = Vec3(0.63, 0.71, 0.81), background_bottom = Vec3(0.93, 0.95, 0.97);
};

//! Camera axes that show a shape upright. view_axes(P) takes them from the principal axes of the
//! vertices (P #V×3): a flat shape (thinnest principal extent below 0.15 of the middle one, e.g. a
//! terrain or the bumpy plane) is seen from above its thinnest axis, anything else stands along its
//! longest (a figure such as the y-up armadillo); each axis is snapped to the nearest coordinate axis, the
//! positive one (meshes are mostly authored so). Where the choice depends on principal directions that are
//! not defined (two variances equal within 1e-6: a sphere, a cube, a cylinder), the bounding box's longest
//! coordinate axis is up (flat: its thinnest), of tied ones the shape's own axis where it has one.
//! Ties (extents or directions within 1e-9) go to the first axis, so the view does not depend on the
//! shape's size or place. `front` is the remaining coordinate axis of smaller
//! extent, so the camera faces the broad side. For the z-up bumpy plane this gives RenderOptions's default.
struct ViewAxes {
  Vec3 up = Vec3::UnitZ(), front = Vec3::UnitY(), side = Vec3::UnitX();  //!< side = front × up
  //! The direction towards the camera at azimuth degrees about up (0: from −front; positive turns towards
  //! −side) and elevation degrees above the horizon. (31, 34.4) is the default −0.6 side − front + 0.8 up.
  Vec3 direction(double azimuth_degrees, double elevation_degrees) const;
  Vec3 default_direction() const { return -0.6 * side - front + 0.8 * up; }
};
//! \throw InvalidInput for no vertices or a non-finite coordinate.
ViewAxes view_axes(const Positions& P);
//! The same with up given (any non-zero vector; front and side from the extents across it).
ViewAxes view_axes(const Positions& P, const Vec3& up);
//! For an edit: a shape that is not flat and whose fixed vertices (indices into P) sit to one side, as
//! feet, a base or a head do (their centroid more than a tenth of the bounding-box diagonal from the
//! vertices' centroid, and their own box at least 5 % of it: a pin of a few vertices does not count),
//! stands along that side's axis: up is the coordinate axis nearest the direction
//! from them to the shape, positive (by the authoring convention, so a figure fixed at its head is not
//! turned upside down). Otherwise view_axes(P).
ViewAxes edit_view_axes(const Positions& P, const std::vector<int>& fixed_vertices);

//! Ray-traces (P #V×3, F #F×3) into an image of options.width × options.height pixels: a pinhole camera
//! on view_direction, placed by options.framing so the whole mesh is visible. Any triangle list is drawn
//! (soups, non-manifold and multi-component meshes); an empty F draws P as a point cloud, one sphere of
//! options.point_radius per vertex. Shading is two-sided Lambert (front and back faces look alike, so a
//! soup's faces need no consistent winding: vertex normals are summed over faces oriented alike where the
//! surface is orientable, see check_surface) from a head light and a key light (upper left, optional
//! shadows) plus ambient and a little specular, with vertex normals interpolated at the hit (a sphere's
//! own normal for points). Rows are traced in parallel. With a scalar and legend = true (and an image of
//! at least 100×60) the right part of the image holds the colour bar.
//! \throw InvalidInput for no vertices, an index out of range, a non-finite coordinate or scalar value, a
//! scalar of the wrong size, or an option out of range (sizes 1..16384, samples 1..16, fov in (0, 170),
//! a zero or non-finite view direction, a negative or non-finite sphere or point radius); Error if Embree
//! fails.
Image render(const Positions& P, const Faces& F, const RenderOptions& options = {});

//! The sphere radius render() gives the points of a cloud (P #V×3) by default: 0.85 × the median distance
//! from a point to its nearest other point, over up to 256 points spread evenly through the ids, each
//! compared with all (O(256·#V), parallel). Neighbouring spheres then overlap, so a scan reads as a
//! surface (a square grid is covered without gaps) while single points stay visible. Coincident points are
//! not neighbours; a single point, or points that all coincide, get radius 1. \throw InvalidInput for no
//! points or a non-finite coordinate.
double default_point_radius(const Positions& P);

//! render() written to path as PNG (atomically). \throw as render() and write_png().
void render_png(const Positions& P, const Faces& F, const std::string& path,
                const RenderOptions& options = {});

//! Encodes image as PNG in memory and writes it atomically (write_file_atomically).
//! \throw InvalidInput for an empty image or a buffer of the wrong size, or an unwritable path; Error if
//! encoding fails.
void write_png(const Image& image, const std::string& path);

//! Contact sheet: tiles laid out row by row in `columns` columns, each in a cell as large as the largest
//! tile, with labels[i] (if given) centred under tile i. \throw InvalidInput for no tiles, columns < 1,
//! an empty tile, or labels that are neither empty nor one per tile.
Image tile_images(const std::vector<Image>& tiles, int columns, const std::vector<std::string>& labels = {});

//! The colour-map range used when RenderOptions leaves it open: [0, p99] for non-negative values
//! (errors), [p1, p99] otherwise (percentiles by nearest rank), widened to a non-empty interval.
//! \throw InvalidInput for an empty vector or a non-finite value.
std::pair<double, double> robust_scalar_range(const Eigen::VectorXd& values);

//! Viridis colour map (piecewise-linear approximation through 9 samples); t is clamped to [0, 1].
Vec3 viridis(double t);

//! #V by 3 sRGB colours of a region's roles, for RenderOptions::vertex_colors: fixed slate blue, free
//! clay (base_color), handle k from a palette (red, green, purple, orange, teal, pink, repeating).
Positions region_colors(const Region& region);

//! Draws text with the built-in 5×7 font, each font pixel a scale × scale block, top-left corner at
//! (x, y); clipped at the image border. Covers ASCII 32..126; anything else draws as a hollow box.
void draw_text(Image& image, int x, int y, const std::string& text, const Vec3& colour, int scale = 1);
//! Width and height in pixels of text drawn at that scale.
int text_width(const std::string& text, int scale = 1);
inline int text_height(int scale = 1) { return 7 * scale; }

}  // namespace msd
