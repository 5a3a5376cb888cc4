#pragma once
//! \file Metrics of a deformation result (design.md §6): handle error, rigidity error (ARAP residual of
//! the one-rings), detail distortion (change of normal-displacement heights over faired bases), volume
//! change of closed meshes, and distance to a reference result. All functions take bulk arrays (#V by 3
//! positions, #F by 3 faces); none modifies its input. Each metric with rest-shape data also comes
//! prepared (RigidityMetric, DetailDistortionMetric, VolumeChangeMetric, and EditMetrics for all of an
//! edit), for measuring several results of one edit.

#include <optional>
#include <vector>

#include "msdeform/core/adjacency.h"
#include "msdeform/core/region.h"
#include "msdeform/core/types.h"
#include "msdeform/decomposition/fairing.h"

namespace msd {

//! Summary of a per-vertex error over a set of vertices.
struct Stats {
  double mean = 0;
  double p95 = 0;  //!< 95th percentile (nearest rank)
  double max = 0;
  int count = 0;  //!< how many values were summarised
};

//! Mean, 95th percentile and maximum of values (all entries). All zero for an empty vector.
Stats summarize(const Eigen::VectorXd& values);
//! The same over values[subset] (indices into values). \throw InvalidInput for an index out of range.
Stats summarize(const Eigen::VectorXd& values, const std::vector<int>& subset);

// ---------------------------------------------------------------------------------------------------
// Handle error

//! How far the constraints are from being met: the largest |p' − T_k p| over vertices of handle k and
//! |p' − p| over fixed vertices, in scene units (0 when the region has no constrained vertex).
//! rest, deformed: #V by 3; region: #V codes; transforms: at least region.num_handles() affine 4x4.
//! \throw InvalidInput if the row counts differ from each other or from the region, or if there are
//! fewer transforms than handles.
double handle_error(const Positions& rest, const Positions& deformed, const Region& region,
                    const std::vector<Mat4>& transforms);

// ---------------------------------------------------------------------------------------------------
// Rigidity error

//! Edge weights w_ij of the one-ring rigidity fit.
enum class RigidityWeights {
  //! Cotangent weights (cot α + cot β)/2 of the rest mesh, as in ARAP; negative weights (obtuse
  //! triangles) are clamped to 0. A vertex whose clamped weights all vanish falls back to uniform.
  Cotan,
  Uniform,  //!< w_ij = 1
};

struct RigidityOptions {
  RigidityWeights weights = RigidityWeights::Cotan;
};

//! Per-vertex rigidity error and its summary.
struct RigidityError {
  //! #V values e_i = min_R Σ_j w_ij |(p'_i − p'_j) − R (p_i − p_j)|² / Σ_j w_ij |p_i − p_j|², R a rotation
  //! (the local step of ARAP, Sorkine & Alexa 2007). Dimensionless and invariant to a common scaling of
  //! rest and deformed. 0 exactly for a rigid motion of the one-ring; a uniform scaling by s gives
  //! (s − 1)², so a 10% stretch reads 0.01; a reflection does not count as rigid. Isolated vertices get 0.
  Eigen::VectorXd per_vertex;
  Stats stats;  //!< over all vertices with at least one neighbour
};

//! The rigidity error prepared from the rest shape: one-rings and (for Cotan) the rest cotan weights are
//! built once, then measure() costs one 3x3 SVD per vertex, in parallel.
class RigidityMetric {
 public:
  //! rest: #V by 3, F: #F by 3. \throw InvalidInput for a face index out of range or a non-finite
  //! coordinate of rest.
  RigidityMetric(const Positions& rest, const Faces& F, const RigidityOptions& options = {});
  //! The error of deformed (#V by 3) against the rest shape. \throw InvalidInput for a row count other
  //! than the rest shape's or a non-finite coordinate (naming the vertex).
  RigidityError measure(const Positions& deformed) const;
  const Positions& rest() const { return rest_; }

 private:
  Positions rest_;
  RigidityOptions options_;
  VertexAdjacency rings_;
  SparseMatrix weights_;          // rest cotan weights W (empty for Uniform)
  std::vector<int> connected_;    // vertices with at least one neighbour
};

//! Rigidity error of deformed against rest (both #V by 3) on faces F (#F by 3), in parallel: one-shot
//! RigidityMetric. \throw InvalidInput for differing row counts, a face index out of range, or a
//! non-finite coordinate.
RigidityError rigidity_error(const Positions& rest, const Positions& deformed, const Faces& F,
                             const RigidityOptions& options = {});

// ---------------------------------------------------------------------------------------------------
// Detail distortion

//! Change of the details, measured as seed 9.3 defines them: B0 = fair_region(S), B1 = fair_region(S')
//! (each faired with the operator of its own geometry), h0 and h1 the normal-displacement heights of S
//! over B0 and of S' over B1 (NormalDisplacements); the distortion of vertex i is |h1_i − h0_i|.
struct DetailDistortion {
  //! #V values |h1 − h0| in scene units on free vertices; 0 on fixed and handle vertices (they are not
  //! faired, so both heights are 0 there).
  Eigen::VectorXd per_vertex;
  //! The normaliser of `stats`: max |h0| over the free vertices, or, for a surface without details
  //! there (max |h0| ≤ 1e-12 · bounding-box diagonal), the bounding-box diagonal of S.
  double scale = 0;
  //! Statistics of per_vertex / scale over the free vertices: details scaled by a factor s everywhere
  //! read max ≈ |s − 1|; an unchanged or rigidly moved surface reads 0.
  Stats stats;
  Eigen::VectorXd rest_heights;      //!< #V h0
  Eigen::VectorXd deformed_heights;  //!< #V h1
  //! Vertices whose base-point search fell back to the closest point (NormalDisplacements::report) in
  //! either encoding; their heights are less reliable.
  int fallback_vertices = 0;
};

//! The detail distortion prepared from the rest shape S: its base B0 = fair_region(S), its heights h0
//! over B0 and the normaliser are computed once. measure() fairs and encodes the deformed shape only (B1
//! is faired with the operator of S', as DetailDistortion defines it).
class DetailDistortionMetric {
 public:
  //! rest: #V by 3 with faces F (#F by 3); region as for the edit (its free vertices are faired).
  //! \throw InvalidInput for a region of another size or without free vertices, a rest mesh of zero
  //! extent, or a faired base B0 that lost the shape (less than kMinBaseAreaRatio of the rest's area on
  //! the triangles with a free vertex, as decompose() refuses it: a large or tube-like free region);
  //! otherwise as fair_region() and NormalDisplacements::encode().
  DetailDistortionMetric(const Positions& rest, const Faces& F, const Region& region,
                         const FairingOptions& fairing = {});
  //! The distortion of deformed (S', #V by 3). \throw InvalidInput for another row count; otherwise as
  //! fair_region() and NormalDisplacements::encode() on S'.
  DetailDistortion measure(const Positions& deformed) const;
  const Eigen::VectorXd& rest_heights() const { return rest_heights_; }  //!< #V h0
  double scale() const { return scale_; }                                //!< DetailDistortion::scale

 private:
  Faces F_;
  Region region_;
  FairingOptions fairing_;
  std::vector<int> free_;
  Eigen::VectorXd rest_heights_;
  int rest_fallback_ = 0;
  double scale_ = 0;
};

//! Detail distortion of deformed (S') against rest (S), both #V by 3 with faces F; region as for the
//! edit (its free vertices are faired): one-shot DetailDistortionMetric. \throw InvalidInput for
//! differing sizes, or as DetailDistortionMetric's constructor and measure().
DetailDistortion detail_distortion(const Positions& rest, const Positions& deformed, const Faces& F,
                                   const Region& region, const FairingOptions& fairing = {});

// ---------------------------------------------------------------------------------------------------
// Volume

//! True if (P, F) is closed and consistently oriented: every directed edge (a, b) of a face is matched
//! by exactly as many uses of (b, a). Meshes with boundaries, or with flipped faces, are not closed.
//! \throw InvalidInput for a face index out of range.
bool is_closed(const Faces& F, int num_vertices);

//! Signed enclosed volume Σ_f p0 · (p1 × p2) / 6 (divergence theorem) of a closed mesh: positive for
//! outward-oriented faces. std::nullopt if the mesh is not closed (is_closed).
//! \throw InvalidInput for a face index out of range or a non-finite coordinate.
std::optional<double> volume(const Positions& P, const Faces& F);

//! The volume change prepared from the rest shape: closedness and the rest volume are computed once.
class VolumeChangeMetric {
 public:
  //! rest: #V by 3, F: #F by 3. \throw as volume().
  VolumeChangeMetric(const Positions& rest, const Faces& F);
  //! V(deformed)/V(rest) − 1 for deformed (#V by 3), at any finite size (volumes measured in units of the
  //! rest's largest bounding-box side); std::nullopt when the mesh is not closed or the rest volume is 0
  //! (deformed is then not read). \throw InvalidInput for another row count and as volume().
  std::optional<double> measure(const Positions& deformed) const;
  const std::optional<double>& rest_volume() const { return rest_volume_; }  //!< std::nullopt if not closed

 private:
  Faces F_;
  Eigen::Index num_vertices_ = 0;
  double unit_ = 1;  // the rest's largest bounding-box side: volumes are compared in this unit
  std::optional<double> rest_volume_;
  double unit_rest_volume_ = 0;  // in units of unit_³
};

//! Relative volume change V(deformed)/V(rest) − 1 (a uniform scaling by s gives s³ − 1). std::nullopt
//! when the mesh is not closed or the rest volume is 0: one-shot VolumeChangeMetric. \throw InvalidInput
//! for differing row counts and as volume().
std::optional<double> volume_change(const Positions& rest, const Positions& deformed, const Faces& F);

// ---------------------------------------------------------------------------------------------------
// Shape change: the cheap check of one result

//! How much a result changed lengths, area and volume around the free region. The linear methods fail
//! under large rotations by shrinking, ballooning or shearing the free region (seed 9.2, 9.4); the space
//! methods pinch and amplify between handles close together (seed 9.5): both show here.
struct ShapeChange {
  long edges = 0;                //!< edges with a free vertex, or between differently placed ones (measured)
  double stretched_share = 0;    //!< of those, the share whose length changed more than 1.5× (grown or shrunk)
  double largest_factor = 1;     //!< the largest change max(l'/l, l/l') of such an edge (inf: one collapsed)
  int largest_vertex = -1;       //!< a vertex of that edge
  double largest_growth = 1;     //!< the largest l'/l of such an edge
  int growth_vertex = -1;        //!< a vertex of that edge
  double largest_shrink = 1;     //!< the largest l/l' of such an edge (inf: collapsed)
  int shrink_vertex = -1;        //!< a vertex of that edge
  double area_ratio = 1;         //!< area of the triangles with a free vertex, deformed over rest
  std::optional<double> volume_change;  //!< closed meshes: V'/V − 1 (volume_change)
};

//! rest, deformed: #V by 3; F: #F by 3 (may be empty: nothing measured); region: #V codes. Edges shorter
//! than 1e-6 of the rest's bounding-box diagonal are skipped: their length changes by rounding-sized
//! amounts that read as large factors (a 1e-7 column widened to 5e-7 read "stretched 5.1 times"). O(#F).
//! \throw InvalidInput for differing row counts or an index out of range.
ShapeChange shape_change(const Positions& rest, const Positions& deformed, const Faces& F, const Region& region);

//! What the handle transforms themselves ask of the shape. A transform's linear part A, with singular
//! values σ1 ≥ σ2 ≥ σ3, stretches an edge by σ3 to σ1, scales a surface's area by σ2σ3 to σ1σ2 and a volume
//! by |det A|; the free region blends the handles with the fixed part (left as it is), so each range
//! includes 1. Rigid handles ask for nothing (all 1); a rotation written with 6 digits (the survey's .def
//! files) asks for factors within 1e-6 of 1.
struct EditScaling {
  double growth = 1;  //!< edges may grow by up to this: the largest of 1 and every σ1
  double shrink = 1;  //!< and shrink by up to this: the largest of 1 and every 1/σ3 (inf: singular)
  double area_low = 1, area_high = 1;      //!< area factors asked: min(1, σ2σ3) to max(1, σ1σ2)
  double volume_low = 1, volume_high = 1;  //!< volume factors asked: min(1, |det A|) to max(1, |det A|)
  bool mirrors = false;                    //!< some det A < 0: a mirrored part turns its volume's sign
  //! How far a volume ratio V'/V lies outside [volume_low, volume_high], relative to the end it passed:
  //! ratio / volume_high − 1 above, 1 − ratio / volume_low below, 0 within (without scaling: |V'/V − 1|).
  double volume_excess(double ratio) const;
};
EditScaling edit_scaling(const std::vector<Mat4>& transforms);

//! Empty, or why the result lost the shape, against what the edit asks (`asked`, edit_scaling()): an edge
//! grown by more than 5× the growth asked or shrunk by more than 5× the shrink asked (a flattened handle
//! asks for any shrink and no growth; a 57× stretch under one went unwarned), tears and collapses (on the
//! benchmark the shell, Laplacian editing, lattice and cages do this under bends and twists, ARAP, gradient
//! editing and deformation transfer stay below 4.5×), the free region's area changed by more than 1.5×
//! area_high or below 2/3 of area_low, or a closed mesh's volume by more than 30 % beyond the range asked
//! (volume_excess; not judged when a handle mirrors). A handle scaled by 1.001 still leaves a +75 % volume
//! change to be warned about (it silenced the area and volume checks altogether).
std::string shape_change_warning(const ShapeChange& change, const EditScaling& asked = {});

// ---------------------------------------------------------------------------------------------------
// All metrics of one edit

struct EditMetricsOptions {
  RigidityOptions rigidity;
  FairingOptions fairing;  //!< of the detail distortion's bases
};

//! The metrics of one result: handle error, rigidity, detail distortion and volume change.
struct EditMeasurement {
  double handle_error = 0;
  RigidityError rigidity;
  DetailDistortion distortion;
  std::optional<double> volume_change;
};

//! The metrics of an edit prepared once from its rest shape, faces and region, then measured for each
//! result of that edit (every method of a comparison): the rest-shape data of rigidity (one-rings, cotan
//! weights), of detail distortion (B0, h0) and of volume change (closedness, rest volume) are computed
//! once. Each measurement returns exactly what the one-shot functions return.
class EditMetrics {
 public:
  //! rest: #V by 3, F: #F by 3, region: #V codes. \throw as RigidityMetric, DetailDistortionMetric and
  //! VolumeChangeMetric.
  EditMetrics(const Positions& rest, const Faces& F, const Region& region, const EditMetricsOptions& options = {});

  //! As handle_error() against the rest shape and region.
  double handle_error(const Positions& deformed, const std::vector<Mat4>& transforms) const;
  RigidityError rigidity(const Positions& deformed) const { return rigidity_.measure(deformed); }
  DetailDistortion detail_distortion(const Positions& deformed) const { return distortion_.measure(deformed); }
  std::optional<double> volume_change(const Positions& deformed) const { return volume_.measure(deformed); }
  //! All four, in that order (the first that throws ends the measurement).
  EditMeasurement measure(const Positions& deformed, const std::vector<Mat4>& transforms) const;

  const Positions& rest() const { return rigidity_.rest(); }
  const Region& region() const { return region_; }

 private:
  Region region_;
  RigidityMetric rigidity_;
  DetailDistortionMetric distortion_;
  VolumeChangeMetric volume_;
};

// ---------------------------------------------------------------------------------------------------
// Distance to a reference result

struct ReferenceDistance {
  double max = 0;       //!< max_i |p_i − q_i| / diagonal
  double mean = 0;      //!< mean_i |p_i − q_i| / diagonal
  double diagonal = 0;  //!< bounding-box diagonal of the reference (the normaliser)
};

//! Vertex-to-vertex distance of P (#V by 3, faces F) to a reference result (Q, FQ) of the same mesh,
//! relative to the reference's bounding-box diagonal.
//! \throw InvalidInput if the vertex counts or the faces differ (naming the first differing face), if the
//! reference's diagonal is 0, or a coordinate is non-finite.
ReferenceDistance distance_to_reference(const Positions& P, const Faces& F, const Positions& Q,
                                        const Faces& FQ);

}  // namespace msd
