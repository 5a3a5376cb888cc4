#pragma once
//! \file Running several editing methods on one edit and measuring each result: the engine of
//! `msdeform compare` and of the regression suites (library target msd::compare). It sits above
//! reconstruction (the named methods) and analysis (the metrics); edits come from core/edit_case.h.

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "msdeform/analysis/metrics.h"
#include "msdeform/core/edit_case.h"
#include "msdeform/reconstruction/catalogue.h"

namespace msd {

//! What one method did on one edit case.
struct MethodResult {
  std::string scene, method;
  int vertices = 0;
  bool ok = false;
  std::string error;  //!< why the method failed (ok = false)
  //! ok = false because the method does not take this kind of input (a surface method on a point cloud or a
  //! non-manifold soup): a refusal the input asks for, not a failure of the run
  bool refused_input = false;
  //! prepare(); a frame: linear methods the median of the timed frames after a warm-up, iterative
  //! methods their one frame from rest.
  double prepare_ms = 0, frame_ms = 0;
  double handle_error = 0;              //!< max |p' − T p| over handle and fixed vertices
  //! One-ring rotation residual (rigidity_error); count 0 when not measured (not_measured says why).
  Stats rigidity;
  //! Detail distortion, relative to the largest detail height; count 0 when not measured.
  Stats distortion;
  //! Intersecting face pairs the edit added: pairs of faces that intersect nothing in the input (a contact of
  //! the input that slides stays the input's; -1: not measured).
  int self_intersections = -1;
  int rest_self_intersections = 0;      //!< intersecting face pairs of the input itself (not counted above)
  std::vector<int> self_intersecting_faces;  //!< the faces of the added pairs (rows of F, a face once per pair)
  int folded_faces = -1;                //!< the method's own frame check (FrameReport; -1: not measured)
  int iterations = 0;                   //!< iterative methods: iterations of the last frame (FrameReport)
  std::string warning;                  //!< what the method warned about (prepare and frame warnings)
  //! Which metrics this result lacks and why, e.g. "point cloud: no faces, so rigidity, detail distortion,
  //! self-intersections and volume change are not measured"; empty when all were measured (a volume change
  //! of an open mesh, or self-intersections switched off in the options, need no reason).
  std::string not_measured;
  std::optional<double> volume_change;  //!< relative, for closed meshes
  EditScaling scaling;  //!< what the handle transforms ask of area and volume (edit_scaling())
  //! Vertex-to-vertex distance to the reference method's result on the same edit, relative to its
  //! bounding-box diagonal (ComparisonOptions::reference; empty when there is none).
  std::optional<ReferenceDistance> reference;
  Positions result;                     //!< #V by 3 deformed positions
  Eigen::VectorXd distortion_per_vertex;  //!< #V |Δh| in scene units (empty when not measured)
};

struct ComparisonOptions {
  std::vector<std::string> methods = builtin_methods().names();  //!< catalogue names (reconstruction/catalogue.h)
  MethodSettings settings;  //!< the methods' options (for a subdivision base: the edit case's control mesh by default)
  //! A method of `methods` whose result the others are measured against (seed Fig. 9.16: the nonlinear
  //! reference); empty: none. \throw InvalidInput from compare_methods() if it is not in `methods`.
  std::string reference;
  int timed_frames = 3;            //!< linear methods: frames timed after one warm-up frame
  bool self_intersections = true;  //!< count intersecting face pairs (CGAL; the costliest metric)
  //! Called with a line of progress (which scene, which method, how long).
  std::function<void(const std::string&)> progress;
};

//! Checks the options before any work: every method name known and listed once, the reference (when
//! given) among them. \throw InvalidInput naming the first fault.
void check_comparison(const ComparisonOptions& options);

//! Runs each method on the case and measures the result. The metrics' rest-shape data (RigidityMetric,
//! DetailDistortionMetric, VolumeChangeMetric) are prepared once per call, not once per method. A method
//! that throws, or returns a non-finite position, is recorded with ok = false and its message; the others
//! still run. A metric that the input cannot give is left unmeasured and the result says why
//! (MethodResult::not_measured), but it never fails the method: a point cloud (no faces) has no rigidity,
//! detail distortion, self-intersections or volume; a soup's faces give rigidity (one-ring edges) and, where
//! its free vertices can be faired, detail distortion, while CGAL counts self-intersections only on a
//! manifold, consistently oriented surface.
std::vector<MethodResult> compare_methods(const EditCase& edit, const ComparisonOptions& options);

//! Of the successful multi-scale results ("multiscale-<encoding>") on `scene`, the one closest to the
//! reference (mean distance), or without a reference the one with the least mean detail distortion: the
//! "shell + multi-scale" row of the seed's Fig. 9.16. nullptr when there is none.
const MethodResult* best_multiscale(const std::vector<MethodResult>& results, const std::string& scene);

//! Why some metrics of the results are n/a, one line per scene and reason, "<scene>: <not_measured>", in
//! the order of the results; empty when every metric was measured. The notes above the metrics tables.
std::vector<std::string> measurement_notes(const std::vector<MethodResult>& results);

//! The results as a table of text cells: the header (column names) first, then one row per result.
//! Failed runs have empty measured cells (a 0 would read as perfect); unmeasured ones read "n/a", and the
//! column not_measured says why.
std::vector<std::vector<std::string>> metrics_table(const std::vector<MethodResult>& results);
//! The results as a CSV table (one row per result, a header line first).
std::string metrics_csv(const std::vector<MethodResult>& results);
//! The results as a Markdown table, preceded by the measurement_notes (a paragraph each) if there are any.
std::string metrics_markdown(const std::vector<MethodResult>& results);

}  // namespace msd
