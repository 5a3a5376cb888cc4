#pragma once
// Regions and handle transforms built on the command line, so an edit needs no hand-written .sel or .def:
//   --fixed SPEC / --handle SPEC (repeatable; each --handle starts the next handle, later selections win)
//     box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX   sphere:X,Y,Z,R   halfspace:NX,NY,NZ,D (n·p < d)
//     vertex:ID,RINGS (the vertex and RINGS rings of neighbours)
//     file:PATH (a .sel: its fixed vertices for --fixed, its handle vertices for --handle)
//     file:PATH,VALUE (the vertices with that value: a .sel code or a .dmat group)
//   --translate X,Y,Z   --rotate AX,AY,AZ,DEGREES [--about X,Y,Z|handle-centroid]   --scale S|SX,SY,SZ [--about ...]
//     composed in the order given; a transform after --handle k moves handle k, one before any --handle
//     moves every handle. A rotation or scale is about the point of the --about right after it, else about
//     the handle's centroid where the transforms before put it.
//   --write-sel PATH / --write-def PATH save the region and transforms built, for other tools.

#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "msdeform/core/edit_case.h"

namespace msd::cli {

struct RegionOptions {
  std::string write_sel, write_def;

  // with_transforms: also --translate, --rotate, --scale, --about and --write-def (the commands that apply
  // handle transforms; the others do not offer them).
  void add_to(CLI::App& cmd, bool with_transforms = true);
  bool builds_region() const;      // a --fixed or --handle was given
  bool builds_transforms() const;  // a --translate, --rotate, --scale or --about was given
  std::vector<std::string> input_files() const;  // the files of file: selections (never to be overwritten)
  // The region of P (faces F for vertex rings) from the selections. \throw InvalidInput naming the
  // option and its value: malformed numbers, an id out of range, a selection that selects nothing.
  Region build_region(const Positions& P, const Faces& F) const;
  // One transform per handle of `region` from the transform options (identity where none applies).
  // \throw InvalidInput as build_region, or for a transform after a --handle that does not exist.
  std::vector<Mat4> build_transforms(const Positions& P, const Region& region) const;

 private:
  struct Step {
    const CLI::Option* option;
    std::string value;
  };
  // Every region and transform option given, in command-line order.
  std::vector<Step> steps() const;
  CLI::App* group_ = nullptr;  // the option group holding them: CLI11 records the order per group
  std::vector<std::string> fixed_values_, handle_values_, translate_values_, rotate_values_, scale_values_,
      about_values_;
  CLI::Option *fixed_ = nullptr, *handle_ = nullptr, *translate_ = nullptr, *rotate_ = nullptr, *scale_ = nullptr,
              *about_ = nullptr;
};

}  // namespace msd::cli
