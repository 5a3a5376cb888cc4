#pragma once
//! \file The editing seam: every deformation method (surface or space, linear or iterative, multi-scale)
//! is a Deformer. It is prepared once from arrays (positions, faces that may be none or a soup, a region)
//! and then driven frame by frame, so the command line, the comparison and the tests treat all methods
//! alike and read what each one can do from its traits.

#include <functional>
#include <string>
#include <vector>

#include "msdeform/core/local_frame.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/region.h"

namespace msd {

//! Where a method works (seed 9.1–9.4 surface methods, 9.5–9.6 space deformations).
enum class DeformerDomain {
  Surface,  //!< deforms the mesh's own vertices through its triangles; prepare() needs faces
  Space,    //!< deforms the space around the shape: any points, with or without faces (evaluate())
};

//! How a frame is computed.
enum class DeformerSolve {
  //! a fixed linear map of the handle data: O(#V); a frame without warnings allocates nothing on the heap
  //! once `out` is sized
  Linear,
  Iterative,  //!< iterations from an initial guess (the last frame, set_initial_guess(), or rest after reset())
};

//! What a method declares about itself; the conformance tests check every promise made here.
struct DeformerTraits {
  DeformerDomain domain = DeformerDomain::Surface;
  DeformerSolve solve = DeformerSolve::Linear;
  //! Accepts explicit target positions for the constrained vertices (deform_to()), not only one affine
  //! transform per handle.
  bool vertex_targets = false;
  //! Iterative methods whose iterations run on the output positions: set_initial_guess() seeds the next
  //! frame. (A multi-scale method iterates on its base and detail heights; it warm-starts from the last
  //! frame and restarts with reset().)
  bool initial_guess = false;
  //! Fixed vertices stay and handle vertices reach T_k p exactly (to round-off). False: the constraints
  //! are met in the least-squares sense (e.g. a coarse lattice), and the frame report says by how much.
  bool exact_constraints = true;
  //! Moving every constrained vertex by one rigid motion moves the whole shape by it. Every method
  //! reproduces translations; linear surface methods do not reproduce rotations of a curved surface
  //! (seed 9.4: they deform displacements, not rotations).
  bool reproduces_rigid_motions = true;
  //! Surface methods that weigh the mesh with the cotan Laplacian (core/laplacian.h): prepare warns where
  //! its zero-area and needle triangles cut the surface. False for PriMo and Euclidean propagation.
  bool cotan_laplacian = true;
};

//! How a handle's vertices spread at rest: their second moments about their centroid (3×3: the mean of
//! (p − c)(p − c)ᵀ; zero when they all lie within 1e-9 of P's bounding-box diagonal of one point), the
//! directions they do not spread in (variance at most 1e-6 of the total: a spread below 1e-3 of the
//! handle's size; every direction for a handle at one point) as a projector, and how many they do spread in.
struct HandleSpread {
  Mat3 scatter = Mat3::Zero();
  Mat3 unspread = Mat3::Zero();
  int spread = 3;
};

//! What the last frame measured about its own result: a frame never returns a result that was not
//! checked. Fields a method does not measure keep their defaults.
struct FrameReport {
  int iterations = 0;      //!< iterative methods: iterations of the frame (0 for linear ones)
  double residual = -1;    //!< iterative methods: relative residual at exit (−1: not measured)
  bool converged = true;   //!< false when an iterative method stopped at its iteration limit
  //! Multi-scale methods: triangles of S' whose normal turned against the deformed base's, relative to
  //! the rest pose (local self-intersections of the details, seed 9.3.3 and Fig. 9.10).
  int folded_faces = -1;
  //! Largest distance of a constrained vertex from its target (measured by methods that do not meet the
  //! constraints exactly; −1: not measured).
  double constraint_error = -1;
  //! Iterative methods that choose their start (ARAP): "last result", "initial guess" (set_initial_guess()'s
  //! X) or "cold start" (one global step with the handles' blended rotations), whichever had the lower
  //! energy; a guess above the cold start's energy is not used. nullptr where the method has one start.
  const char* start = nullptr;
  //! What the user should know about this frame (folds, no convergence), each naming a remedy. Empty in
  //! a clean frame (clearing it allocates nothing).
  std::vector<std::string> warnings;
};

//! Maps handle data to deformed positions. prepare() once per shape and region (factorisations, basis
//! fields); then deform() per frame. Not thread-safe: a frame may use internal workspace.
class Deformer {
 public:
  virtual ~Deformer() = default;
  //! Short method name, e.g. "shell", "propagate", "multiscale-normal" (stored: no allocation per call).
  virtual const std::string& name() const = 0;
  virtual DeformerTraits traits() const = 0;

  //! Precomputes everything that depends only on the rest shape and the region. P: #V by 3 positions;
  //! F: #F by 3 triangles (surface methods need at least one; space methods take none or a soup);
  //! region: #V codes with at least one handle. Checks the arrays (finite, indices in range) and the
  //! region (Region::validate, with F for surface methods). Surface methods also check F as load_mesh does
  //! (check_surface): a non-manifold edge or vertex, a non-orientable patch, a face repeating a vertex or
  //! repeating another face is a TopologyError; faces wound against their neighbours give a prepare warning.
  //! \throw InvalidInput, TopologyError, SolverError naming what is wrong.
  void prepare(const Positions& P, const Faces& F, const Region& region);
  //! The same from a Mesh (converted once).
  void prepare(const Mesh& mesh, const Region& region);

  //! One frame: transforms[k] moves handle k (4x4 affine). Writes #V by 3 positions into out (resized
  //! only when its shape differs). A transform that is singular (it flattens or collapses its handle), a
  //! reflection, or a half turn (which way round is not defined) is warned about in the frame report
  //! (handle_transform_warnings()). \throw UsageError before prepare or for a wrong transform count;
  //! InvalidInput for a non-finite or non-affine matrix; SolverError naming the vertex if the result has
  //! a non-finite coordinate.
  void deform(const std::vector<Mat4>& transforms, Positions& out);
  Positions deform(const std::vector<Mat4>& transforms);
  //! One frame with explicit targets: #C by 3 positions, one per vertex of
  //! Region::constrained_vertices() in that order (fixed vertices usually at rest). \throw UsageError
  //! unless traits().vertex_targets, before prepare, or for a wrong row count; InvalidInput for a
  //! non-finite target; SolverError as deform().
  void deform_to(const Positions& targets, Positions& out);

  //! Methods with traits().initial_guess: the next frame starts from X (#V by 3) instead of the last
  //! frame's result (ARAP only where X's energy is below its cold start's: FrameReport::start says).
  //! \throw UsageError for other methods, before prepare, or for a wrong shape; InvalidInput if X is not
  //! finite.
  void set_initial_guess(const Positions& X);
  //! Back to the rest pose: the next frame of an iterative method starts from rest, a space method's map
  //! is the identity again, and the frame report is cleared. Factorisations are kept.
  void reset();

  //! Space methods: the map of the last frame (the identity before the first frame or after reset())
  //! applied to arbitrary points (#N by 3) into out (#N by 3), e.g. a point cloud or another mesh
  //! sharing the space (seed 9.5, 9.6). The map is fitted to the prepared points: beyond them (outside
  //! the lattice's box or the cage, far from the RBF centres) it is the method's extrapolation, which grows
  //! with the distance (1e6 away from the camel, a handle moved by 0.2 moved the point by 4e4 to 7e4).
  //! \throw UsageError for a surface method or before prepare; InvalidInput for a non-finite point;
  //! SolverError for a point the map sends to a non-finite position.
  void evaluate(const Positions& points, Positions& out) const;

  //! Receives a line about long work while it runs: the phases of prepare() (e.g. a multi-scale method's
  //! decomposition, base deformer and encoding) and each iteration of an iterative frame ("arap: iteration
  //! 12, largest move 3.1e-4 of the diagonal"). Called on the calling thread. Empty (the default): nothing
  //! is reported and no text is built, so frames stay allocation-free.
  void set_progress(std::function<void(const std::string&)> callback) { progress_ = std::move(callback); }

  bool prepared() const { return prepared_; }
  const FrameReport& frame_report() const { return frame_report_; }
  //! What prepare() found that the user should know (e.g. details close to folding over a multi-scale
  //! base), each naming a remedy; empty when all is well.
  const std::vector<std::string>& prepare_warnings() const { return prepare_warnings_; }
  int num_handles() const { return num_handles_; }
  int num_vertices() const { return num_vertices_; }

 protected:
  //! Method-specific precomputation; arrays and region are already checked, the region has >= 1 handle.
  virtual void do_prepare(const Positions& P, const Faces& F, const Region& region) = 0;
  //! Method-specific frame; transforms are checked, out has #V rows, frame_report_ is reset to its
  //! defaults. deform() checks afterwards that every position is finite (unless the frame did, see
  //! set_output_checked_finite()).
  virtual void do_deform(const std::vector<Mat4>& transforms, Positions& out) = 0;
  //! Methods with traits().vertex_targets: targets checked (#C by 3, finite), out has #V rows.
  virtual void do_deform_to(const Positions& targets, Positions& out);
  virtual void do_set_initial_guess(const Positions& X);
  virtual void do_reset() {}
  virtual void do_evaluate(const Positions& points, Positions& out) const;

  //! Whether set_progress() gave a callback (build the text only then), and the report itself.
  bool progress_wanted() const { return static_cast<bool>(progress_); }
  void progress(const std::string& line) const {
    if (progress_) progress_(line);
  }
  const std::function<void(const std::string&)>& progress_callback() const { return progress_; }

  FrameReport frame_report_;  //!< filled by the frame where the method measures something
  std::vector<std::string> prepare_warnings_;  //!< filled by do_prepare() (cleared before it)

  //! Frame bracket for frames a subclass adds (e.g. control-point editing): checks prepared, sizes out,
  //! clears the report / checks every position is finite and turns a non-convergence into a warning.
  void begin_frame(Positions& out);
  void end_frame(const Positions& out);
  //! For do_deform() and do_deform_to(): the frame's own passes checked every row of out finite while it
  //! was in the cache (or threw), so end_frame() need not read all of out again (at 1M vertices that scan
  //! costs 1–2 ms once out has left the caches). Call only when every row was checked or copied from data
  //! checked finite before; end_frame() then still turns a non-convergence into a warning.
  void set_output_checked_finite() { output_checked_finite_ = true; }

 private:
  std::function<void(const std::string&)> progress_;
  bool prepared_ = false;
  bool prepare_failed_ = false;         // the last prepare() threw (a frame's error says so)
  bool output_checked_finite_ = false;  // set_output_checked_finite() in this frame
  int num_handles_ = 0, num_vertices_ = 0, num_constrained_ = 0;
  std::vector<HandleSpread> handle_spreads_;  // of the prepared region, for handle_span_warnings
};

//! A deformer whose solver works in the shape's centred, normalised frame (LocalFrame), for methods whose
//! tolerances, damping or rank tests are absolute (PriMo, Laplacian editing). Subclasses implement the
//! *_local functions on local coordinates; positions, transforms and guesses are mapped in and results
//! mapped out here, with the constrained vertices placed exactly at p or T_k·p in the caller's frame (the
//! round trip through the local frame would move them by rounding). Reports that are ratios (residuals,
//! scale checks) are the same in either frame.
class LocalFrameDeformer : public Deformer {
 protected:
  void do_prepare(const Positions& P, const Faces& F, const Region& region) final;
  void do_deform(const std::vector<Mat4>& transforms, Positions& out) final;
  void do_set_initial_guess(const Positions& X) final;
  virtual void prepare_local(const Positions& P, const Faces& F, const Region& region) = 0;
  virtual void deform_local(const std::vector<Mat4>& transforms, Positions& out) = 0;
  //! Default: no initial guess (Deformer's UsageError).
  virtual void set_initial_guess_local(const Positions& X) { Deformer::do_set_initial_guess(X); }
  const LocalFrame& local_frame() const { return local_; }

 private:
  LocalFrame local_;
  std::vector<Mat4> local_transforms_;
  Positions rest_, targets_;  // the caller's frame
  std::vector<int> constrained_, handle_of_;
};

//! In the prepare warning about edges joining vertices that different transforms place (fixed and a
//! handle, or two handles, with no free vertex between them to deform).
constexpr const char* kTornEdgesWarning = "vertices placed by different transforms";
//! In the prepare warning about zero-area triangles that cut the surface into pieces joined only through
//! them (the cotan Laplacian leaves them out).
constexpr const char* kZeroAreaCutWarning = "cut the surface into";
//! In the prepare warning on needle triangles (a corner's cotangent above LaplaceOperator::kMaxCotangent)
//! that cut the surface into pieces joined only through them.
constexpr const char* kNeedleWarning = "have cotangent weights the cotangent Laplacian clamps";
//! In the frame warning of a method that stopped before its tolerance (Deformer::end_frame).
constexpr const char* kNotConvergedWarning = ": stopped after ";

//! In the frame warning about a handle transform that is singular, a reflection or a half turn.
constexpr const char* kHandleTransformWarning = ": the transform of handle ";
//! Appends to `warnings` one line per transform (finite, affine) that is singular (numerical rank below 3:
//! the handle flattened onto a plane, a line or a point), a reflection (negative determinant: the handle
//! turned inside out) or a half turn (180°: methods that blend or iterate rotations may turn it either
//! way); `who` prefixes each. Allocates only for a warning.
void handle_transform_warnings(const std::vector<Mat4>& transforms, const std::string& who,
                               std::vector<std::string>& warnings);

//! One HandleSpread per handle of region (validated against P, #V×3), for handle_span_warnings.
std::vector<HandleSpread> handle_spreads(const Positions& P, const Region& region);
//! Appends a warning for each handle whose transform changes it in directions its vertices do not spread
//! in (a variance at most 1e-6 of the handle's total: a spread below 1e-3 of its size), so that the change
//! moves none of them (third and fourth break tests: a one-vertex handle turned 170°, a flat cap scaled
//! along its normal, a row of vertices twisted about itself left shell's and ARAP's result at rest without a
//! word, while gradient editing and propagation deformed the free region). The turn the moved vertices show
//! is fitted (Procrustes, the least turn where they leave it open); what the transform does beyond it in
//! those directions is warned of when it changes a length there by over 2 %. Methods that place vertices
//! see only the vertices' targets; methods that blend the transform (gradient, propagate) apply all of it.
//! Reflections, singular transforms and half turns are left to handle_transform_warnings. O(1) per handle,
//! nothing for a handle spread in every direction; allocates only for a warning.
void handle_span_warnings(const std::vector<Mat4>& transforms, const std::vector<HandleSpread>& spreads,
                          const std::string& who, std::vector<std::string>& warnings);

//! Throws InvalidInput unless every transform is finite with last row (0 0 0 1); `who` prefixes the message.
void check_affine(const std::vector<Mat4>& transforms, const std::string& who);

//! The targets of an affine frame: #C by 3, row c is p or T_k p for the c-th constrained vertex of the
//! region (Region::constrained_vertices() order), for methods that solve for explicit targets.
void affine_targets(const Positions& rest, const std::vector<int>& constrained, const std::vector<int>& handle_of,
                    const std::vector<Mat4>& transforms, Positions& targets);

}  // namespace msd
