#pragma once
//! \file The editing-operator interface: every deformation method (surface, space, multi-scale) is a
//! Deformer, so the CLI and the comparison app iterate over them by name.

#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/region.h"

namespace msd {

//! What the last frame measured about its own result (the cheap checks: a frame never returns a result
//! that was not checked). Fields a method does not measure stay at −1.
struct FrameReport {
  //! Multi-scale methods: triangles of S' whose normal turned against the deformed base's, relative to
  //! the rest pose (local self-intersections of the details, seed 9.3.3 and Fig. 9.10). O(#F) per frame.
  int folded_faces = -1;
};

//! Maps one affine transform per handle to deformed vertex positions.
//! prepare() once per mesh and region (factorisations, basis fields); deform() per frame: O(#V) and
//! allocation-free once `out` has the right size. Not thread-safe: a frame may use internal workspace.
class Deformer {
 public:
  virtual ~Deformer() = default;
  //! Short method name, e.g. "shell", "propagate", "multiscale".
  virtual std::string name() const = 0;

  //! Precomputes everything that depends only on the rest shape and the region. Validates the region
  //! (see Region::validate) and requires at least one handle.
  //! \throw InvalidInput, TopologyError, SolverError naming what is wrong.
  void prepare(const Mesh& mesh, const Region& region);

  //! One frame: transforms[k] moves handle k (4x4 affine). Writes #V by 3 positions into out (resized
  //! only when its shape differs). \throw UsageError before prepare or for a wrong transform count;
  //! InvalidInput for a non-finite or non-affine matrix; SolverError naming the vertex if the result has
  //! a non-finite coordinate.
  void deform(const std::vector<Mat4>& transforms, Positions& out);
  Positions deform(const std::vector<Mat4>& transforms);

  bool prepared() const { return prepared_; }
  //! What the last deform() measured (see FrameReport).
  const FrameReport& frame_report() const { return frame_report_; }
  int num_handles() const { return num_handles_; }
  int num_vertices() const { return num_vertices_; }

 protected:
  //! Method-specific precomputation; the region is already validated and has >= 1 handle.
  virtual void do_prepare(const Mesh& mesh, const Region& region) = 0;
  //! Method-specific frame; transforms are checked and out has #V rows. deform() checks afterwards that
  //! every position is finite.
  virtual void do_deform(const std::vector<Mat4>& transforms, Positions& out) = 0;

  FrameReport frame_report_;  //!< filled by do_deform() where the method measures something

 private:
  bool prepared_ = false;
  int num_handles_ = 0, num_vertices_ = 0;
};

//! Throws InvalidInput unless every transform is finite with last row (0 0 0 1); `who` prefixes the message.
void check_affine(const std::vector<Mat4>& transforms, const char* who);

}  // namespace msd
