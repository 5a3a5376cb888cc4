#pragma once
//! \file The size range msdeform computes in: squared areas of triangles must fit a double, so positions
//! must span at least 1e-70 and stay below 1e70 (mesh units).

#include <string>

#include "msdeform/core/types.h"

namespace msd {

//! Smallest bounding-box diagonal and largest |coordinate| that every computation holds.
constexpr double kMinExtent = 1e-70, kMaxExtent = 1e70;

//! x with 3 significant digits ("%.3g"), for messages about sizes.
std::string format_number(double x);

//! Refuses positions P (#V by 3; none is fine) with no extent (every vertex at one point), a bounding-box
//! diagonal below kMinExtent, or a diagonal or a coordinate of kMaxExtent or more. Coordinates must be finite (checked
//! before). \throw InvalidInput starting with `who`, naming the diagonal and the largest |coordinate|.
void check_extent(const Positions& P, const std::string& who);

//! Empty, or a warning starting with `who` when a few stray vertices set the bounding box (a scan's stray
//! points, a vertex at the origin): the box's diagonal is more than 10 times that of the box left without the
//! k most extreme coordinates at each end of each axis (k = #V / 1000, at least min(5, #V / 100) and 1), and
//! the vertex farthest outside that box lies more than 100 median edge lengths of F from it (F may be empty:
//! a point cloud; then the box alone decides). A coarse cone's apex is far from the rest too, but not in
//! edge lengths. Tolerances given in bounding-box diagonals (ARAP's and PriMo's stopping tests, constraint
//! errors) are then that many times looser than meant. The warning names the farthest vertex. P is #V by 3,
//! F #F by 3; O(#V + #F).
std::string extent_outlier_warning(const Positions& P, const Faces& F, const std::string& who);
//! The words every such warning holds (for a caller that gathers warnings of nested deformers once).
constexpr const char* kOutlierWarning = "a few outlying vertices set the bounding box";

}  // namespace msd
