#pragma once
//! \file Transitional names for the catalogue (reconstruction/catalogue.h); to be removed.

#include "reconstruction/catalogue.h"

namespace msd {

using MethodOptions = MethodSettings;
inline std::vector<std::string> method_names() { return builtin_methods().names(); }
inline std::unique_ptr<Deformer> make_deformer(const std::string& name, const MethodOptions& options = {}) {
  return builtin_methods().make(name, options);
}

}  // namespace msd
