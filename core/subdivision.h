#pragma once
//! \file Uniform Loop refinement of triangle meshes (OpenSubdiv Far), as sparse stencil matrices.

#include "msdeform/core/types.h"

namespace msd {

//! The result of refining a coarse triangle mesh `levels` times: the fine connectivity and two
//! #fine by #coarse stencil matrices, so fine positions are one sparse product of coarse ones.
struct LoopRefinement {
  Faces faces;          //!< connectivity of the finest level
  SparseMatrix loop;    //!< Loop subdivision (boundary as cubic B-spline, corners kept)
  SparseMatrix linear;  //!< midpoint (linear) refinement: the fine mesh flat on the coarse triangles
  int levels = 0;
};

//! A coarse control mesh together with its refinement: a mesh whose faces are refinement.faces is the
//! Loop subdivision surface of P (the generated scenes carry one; see core/scenes.h).
struct ControlMesh {
  Positions P;  //!< #coarse by 3
  Faces F;      //!< #coarse faces by 3
  LoopRefinement refinement;
};

//! Refines the coarse connectivity (F, over num_vertices vertices) `levels` times (0 to 10).
//! \throw InvalidInput on an index out of range or a level count out of range; TopologyError if
//! OpenSubdiv rejects the topology.
LoopRefinement loop_refine(const Faces& F, int num_vertices, int levels);

}  // namespace msd
