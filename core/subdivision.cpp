#include "msdeform/core/subdivision.h"

#include <memory>
#include <vector>

#include <opensubdiv/far/stencilTable.h>
#include <opensubdiv/far/stencilTableFactory.h>
#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/far/topologyRefinerFactory.h>

#include "msdeform/core/errors.h"

namespace msd {
namespace {

using namespace OpenSubdiv;

SparseMatrix stencil_matrix(const Far::TopologyRefiner& refiner, int levels, int num_coarse, unsigned mode) {
  Far::StencilTableFactoryReal<double>::Options options;
  options.interpolationMode = mode;
  options.generateIntermediateLevels = false;
  options.generateOffsets = true;
  options.maxLevel = levels;
  std::unique_ptr<const Far::StencilTableReal<double>> table(Far::StencilTableFactoryReal<double>::Create(refiner, options));
  const int n = table->GetNumStencils();
  std::vector<Triplet> triplets;
  triplets.reserve(table->GetWeights().size());
  for (int i = 0; i < n; ++i) {
    const auto stencil = table->GetStencil(i);
    for (int k = 0; k < stencil.GetSize(); ++k)
      triplets.emplace_back(i, stencil.GetVertexIndices()[k], stencil.GetWeights()[k]);
  }
  SparseMatrix S(n, num_coarse);
  S.setFromTriplets(triplets.begin(), triplets.end());
  return S;
}

}  // namespace

LoopRefinement loop_refine(const Faces& F, int num_vertices, int levels) {
  if (levels < 0 || levels > 10)
    throw InvalidInput("loop_refine: " + std::to_string(levels) + " levels requested (0 to 10 supported)");
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k)
      if (F(f, k) < 0 || F(f, k) >= num_vertices)
        throw InvalidInput("loop_refine: face " + std::to_string(f) + " has vertex index " + std::to_string(F(f, k)) + " out of range");
  LoopRefinement out;
  out.levels = levels;
  if (levels == 0) {
    out.faces = F;
    out.loop.resize(num_vertices, num_vertices);
    out.loop.setIdentity();
    out.linear = out.loop;
    return out;
  }
  std::vector<int> corners_per_face(F.rows(), 3);
  std::vector<int> indices(F.data(), F.data() + F.size());
  Far::TopologyDescriptor desc;
  desc.numVertices = num_vertices;
  desc.numFaces = static_cast<int>(F.rows());
  desc.numVertsPerFace = corners_per_face.data();
  desc.vertIndicesPerFace = indices.data();
  Sdc::Options sdc;
  sdc.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_AND_CORNER);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> refiner(Factory::Create(desc, Factory::Options(Sdc::SCHEME_LOOP, sdc)));
  if (!refiner) throw TopologyError("loop_refine: OpenSubdiv rejected the mesh topology (non-manifold?)");
  Far::TopologyRefiner::UniformOptions uniform(levels);
  uniform.fullTopologyInLastLevel = true;
  refiner->RefineUniform(uniform);
  const Far::TopologyLevel& last = refiner->GetLevel(levels);
  out.faces.resize(last.GetNumFaces(), 3);
  for (int f = 0; f < last.GetNumFaces(); ++f) {
    const auto fv = last.GetFaceVertices(f);
    for (int k = 0; k < 3; ++k) out.faces(f, k) = fv[k];
  }
  out.loop = stencil_matrix(*refiner, levels, num_vertices, Far::StencilTableFactoryReal<double>::INTERPOLATE_VERTEX);
  out.linear = stencil_matrix(*refiner, levels, num_vertices, Far::StencilTableFactoryReal<double>::INTERPOLATE_VARYING);
  return out;
}

}  // namespace msd
