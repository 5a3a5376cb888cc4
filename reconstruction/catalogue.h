#pragma once
//! \file The catalogue of editing methods: a table of rows (name, what it is, how to build it from the
//! typed settings), which the command line, the comparison and the conformance tests iterate over. A new
//! method is one Deformer file plus one row; tests add rows of their own (Catalogue::add) without
//! touching the built-in table.

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "msdeform/deformation/arap.h"
#include "msdeform/deformation/cage.h"
#include "msdeform/deformation/deformer.h"
#include "msdeform/deformation/gradient_editing.h"
#include "msdeform/deformation/laplacian_editing.h"
#include "msdeform/deformation/lattice.h"
#include "msdeform/deformation/primo.h"
#include "msdeform/deformation/propagation.h"
#include "msdeform/deformation/rbf.h"
#include "msdeform/deformation/shell.h"
#include "msdeform/reconstruction/multiscale.h"

namespace msd {

//! Every method's typed options; each row reads the parts that concern it.
struct MethodSettings {
  ShellOptions shell;                  //!< shell (and the base of multiscale-* with base_method "shell")
  PropagationOptions propagation;      //!< propagate
  LaplacianEditingOptions laplacian;   //!< laplacian
  ArapOptions arap;                    //!< arap
  PrimoOptions primo;                  //!< primo
  LatticeOptions lattice;              //!< lattice
  CageOptions cage;                    //!< cage-mvc and cage-harmonic (the coordinates come from the name)
  RbfOptions rbf;                      //!< rbf
  DecompositionOptions decomposition;  //!< multiscale-*: how S is split into B and details
  EncodingOptions encoding;            //!< multiscale-*: the encodings' options (the kind comes from the name)
  //! multiscale-*: the catalogue method that deforms the base (any single-scale row).
  std::string base_method = "shell";
};

class Catalogue;

//! Whether a catalogue name is a multi-scale method (multiscale-vectors, -normal, -volumes, -transfer).
inline bool is_multiscale(const std::string& method) { return method.rfind("multiscale", 0) == 0; }

//! One row of the catalogue.
struct MethodEntry {
  std::string name;     //!< e.g. "shell", "multiscale-normal"
  std::string section;  //!< where the seed describes it, e.g. "9.2"
  std::string summary;  //!< one line: what it is
  //! Builds the method from the settings; the catalogue is passed for methods composed of others.
  //! Throws InvalidInput for invalid settings. Constructors do no heavy work: building one to read its
  //! traits() is cheap.
  std::function<std::unique_ptr<Deformer>(const MethodSettings&, const Catalogue&)> make;
};

class Catalogue {
 public:
  //! Appends a row. \throw InvalidInput for an empty name, a name already present, or no factory.
  void add(MethodEntry entry);
  const std::vector<MethodEntry>& entries() const { return entries_; }
  std::vector<std::string> names() const;
  //! The row of a name. \throw InvalidInput for an unknown name, listing the known ones.
  const MethodEntry& find(const std::string& name) const;
  //! The named method, configured. \throw InvalidInput for an unknown name or invalid settings.
  std::unique_ptr<Deformer> make(const std::string& name, const MethodSettings& settings = {}) const;

 private:
  std::vector<MethodEntry> entries_;
};

//! The built-in methods: "shell", "propagate", "gradient", "laplacian", then "multiscale-<encoding>" for each detail encoding.
const Catalogue& builtin_methods();

}  // namespace msd
