#pragma once
//! \file The detail-encoding interface D = S ⊖ B and reconstruction S' = B' ⊕ D (seed 9.3).

#include <string>
#include <vector>

#include "msdeform/core/errors.h"
#include "msdeform/core/types.h"

namespace msd {

//! A detail encoding. encode() once for a detailed surface S and its base B; reconstruct() per frame
//! from a deformed base B' (same connectivity as B): O(#V) and allocation-free once `out` is sized.
class DetailEncoding {
 public:
  virtual ~DetailEncoding() = default;
  //! Short name, e.g. "vectors", "normal".
  virtual std::string name() const = 0;
  //! True if encode() needs S and B to share connectivity (Fs = Fb), so the base cannot be remeshed.
  virtual bool needs_same_connectivity() const { return false; }
  //! True if reconstruct() iterates (its result then depends on the previous frame, see reset()).
  virtual bool iterative() const { return false; }
  //! Iterative encodings: forget the previous frame, so the next reconstruct() starts from the encoding.
  virtual void reset() {}
  //! Iterative encodings: iterations and relative residual of the last reconstruct(), and whether it met
  //! its tolerance (0, −1, true for direct ones).
  virtual int last_iterations() const { return 0; }
  virtual double last_residual() const { return -1; }
  virtual bool last_converged() const { return true; }
  //! What encode() could not do exactly, in words (e.g. vertices whose base point search fell back).
  virtual std::vector<std::string> encode_warnings() const { return {}; }
  //! Vertices of S that an edit constrains (fixed and handle vertices). Encodings that solve a global
  //! system for S' (deformation transfer) use them as Dirichlet constraints; the others ignore them.
  //! Call before encode(). \throw InvalidInput on an index out of range at encode().
  virtual void set_anchor_vertices(std::vector<int> vertices) { anchors_ = std::move(vertices); }
  const std::vector<int>& anchor_vertices() const { return anchors_; }
  //! Vertices of S whose rows of S' the caller writes itself, before every reconstruct() (the multi-scale
  //! deformer places its fixed and handle vertices exactly where the edit puts them). reconstruct() then
  //! needs out with #Vs rows on entry, leaves those rows as they are, and skips the work only they need:
  //! normal displacements and vectors their interpolation and the base normals or frames no other vertex
  //! reads (they then check only the rows of B' they read); deformation transfer takes the Dirichlet
  //! values of its placed anchors from those rows, so its Poisson solve ends at the positions returned
  //! there, and reconstructs only the others. Empty by default. Call before encode(); encode() throws
  //! InvalidInput on an index out of range.
  void set_placed_vertices(std::vector<int> vertices) { placed_ = std::move(vertices); }
  const std::vector<int>& placed_vertices() const { return placed_; }

  //! S: #Vs by 3 detailed positions with faces Fs; B: #Vb by 3 base positions with faces Fb. Encodings
  //! that need S and B to share connectivity throw InvalidInput when they do not.
  virtual void encode(const Positions& S, const Faces& Fs, const Positions& B, const Faces& Fb) = 0;
  //! Writes S' (#Vs by 3) for the deformed base B' (#Vb by 3) into out. Every row it writes is finite: a
  //! row that is not (e.g. from a finite B' whose edges overflow) is an error (MultiscaleDeformer relies
  //! on it and does not scan S' again).
  //! \throw UsageError before encode(), when B' has the wrong size, or when out is B_deformed itself (S' is
  //! written while B' is still read); InvalidInput or SolverError when a row of S' would not be finite.
  virtual void reconstruct(const Positions& B_deformed, Positions& out) = 0;

 protected:
  //! \throw UsageError naming `where` when out is B_deformed itself.
  static void check_not_aliased(const Positions& B_deformed, const Positions& out, const char* where) {
    if (&B_deformed == &out)
      throw UsageError(
          std::string(where) +
          ": out is the deformed base itself; S' is written while B' is read, pass another matrix");
  }

  //! Sizes out to num_vertices rows for reconstruct(). With placed vertices their rows must be there
  //! already: \throw UsageError naming `where` when out has another number of rows.
  void size_output(Positions& out, long num_vertices, const char* where) const {
    if (out.rows() == num_vertices && out.cols() == 3) return;
    if (!placed_.empty())
      throw UsageError(std::string(where) + ": out has " + std::to_string(out.rows()) + " rows; with placed vertices " +
                       "it must have S's " + std::to_string(num_vertices) + ", the placed rows written by the caller");
    out.resize(num_vertices, 3);
  }

  //! placed_vertices() as a mask over the num_vertices vertices of S.
  //! \throw InvalidInput naming `where` on an index out of range.
  std::vector<char> placed_mask(long num_vertices, const char* where) const {
    std::vector<char> mask(num_vertices, 0);
    for (int v : placed_) {
      if (v < 0 || v >= num_vertices)
        throw InvalidInput(std::string(where) + ": placed vertex " + std::to_string(v) + " is out of range [0, " +
                           std::to_string(num_vertices) + ")");
      mask[v] = 1;
    }
    return mask;
  }

  std::vector<int> anchors_, placed_;
};

}  // namespace msd
