#pragma once
//! \file Every editing method msdeform can build, by name: the command line and the comparison app
//! iterate over these.

#include <memory>
#include <string>
#include <vector>

#include "decomposition/fairing.h"
#include "deformation/deformer.h"
#include "deformation/propagation.h"
#include "deformation/shell.h"
#include "reconstruction/multiscale.h"

namespace msd {

//! Settings shared by the named methods (each method reads the parts that concern it).
struct MethodOptions {
  ShellOptions shell;               //!< shell, and the base operator of every multiscale-* method
  PropagationOptions propagation;   //!< propagate
  BaseKind base = BaseKind::LowPass;               //!< multiscale-*: how the base is computed
  LowPassOptions low_pass;                         //!< multiscale-*: detail scale (0 = automatic)
  FairingOrder fairing = FairingOrder::ThinPlate;  //!< multiscale-* with BaseKind::Fairing
  double remesh_base_edge_length = 0;  //!< multiscale-*: > 0 remeshes the base isotropically (CGAL)
};

//! "shell", "propagate", then "multiscale-<encoding>" for each detail encoding.
std::vector<std::string> method_names();

//! The named method, configured. \throw InvalidInput for an unknown name (listing the known ones) or
//! invalid options.
std::unique_ptr<Deformer> make_deformer(const std::string& name, const MethodOptions& options = {});

}  // namespace msd
