#pragma once
// Command-line options that choose an edit: mesh files or a built-in scene (loaded by core/edit_case.h).

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "apps/msdeform/region_options.h"
#include "msdeform/core/atomic_file.h"  // same_file, check_writable
#include "msdeform/core/edit_case.h"

namespace msd::cli {

struct EditCaseOptions {
  std::string mesh, sel, def, scene, resolution = "10k";
  bool force = false;  // --force: an output may replace an input file
  RegionOptions region;  // --fixed, --handle, --translate, ...: the region and transforms without files
  // with_transforms: also --def and the transform options (RegionOptions::add_to); the commands that apply
  // no handle transforms (decompose, render) leave them out.
  void add_to(CLI::App& cmd, bool with_transforms = true);
  // Before any work: output (named by option, e.g. "-o") has a known mesh format and can be written
  // (check_writable), and is none of the inputs (the edit's files and other_inputs) unless --force.
  // Warns that an STL output will not keep the input's vertices. Throws InvalidInput naming the option
  // and the path.
  void check_output(const std::string& output, const char* option,
                    const std::vector<std::string>& other_inputs = {}) const;
  // Loads the files or builds the scene, and builds the region and transforms given on the command line.
  // Throws InvalidInput naming the file, option or mismatch, also when --write-sel / --write-def have
  // nothing to write. Without need_transforms, --def may be omitted (transforms stay empty); without
  // need_region, --sel too (the region stays empty).
  EditCase load(bool need_transforms = true, bool need_region = true) const;
  // Writes the region and transforms (as load() built them, on the file's vertices) where --write-sel /
  // --write-def ask. Commands call it once their work has succeeded, so a failed run leaves those files
  // as they were.
  void write_built(const Region& region, const std::vector<Mat4>& transforms) const;
};

// Says on stderr ("note: FILE: …") when loading `c` from mesh file `mesh` dropped or re-wound faces
// (faces_changed_on_load), so that the meshes a command writes are not taken for the file's faces.
void note_faces_changed(const EditCase& c, const std::string& mesh);

}  // namespace msd::cli
