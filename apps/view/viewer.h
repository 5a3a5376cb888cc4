#pragma once
// The interactive viewer (msdeform view): a GLFW window with OpenGL 3.3 and a Dear ImGui panel, over the
// library's catalogue of methods. Built only when GLFW and Debian's imgui are found (MSD_HAVE_VIEWER).

#include <string>
#include <vector>

#include "msdeform/core/edit_case.h"
#include "msdeform/reconstruction/catalogue.h"

namespace msd::view {

struct ViewerOptions {
  EditCase edit;                 // the mesh (faces required), its region and transforms (either may be empty)
  std::string method = "arap";   // catalogue name
  MethodSettings settings;       // the methods' settings (the panel edits a few of them)
  int iterations_per_frame = 5;  // nonlinear methods: iterations per drawn frame; they go on while idle
  Vec3 up = Vec3::UnitZ();       // world axis drawn upwards
  Vec3 view_direction = Vec3::Zero();  // towards the camera (zero: the still pictures' default)
  int width = 1280, height = 800;
  std::string script;      // commands run one per drawn frame (interaction.h, read_script)
  std::string screenshot;  // after the script: the 3D view to this PNG, then exit
  bool quiet = false;      // no per-command lines on stdout in the scripted mode
  std::vector<std::string> inputs;  // files the viewer read (mesh, region, transforms, script): never written
};

// Opens the window and runs until it is closed (or the scripted run ends with a screenshot). Prints what
// the scripted mode did (one line per command, with prepare and frame times). Returns 0, or 1 if a script
// command failed (the message names the script line). \throw InvalidInput for a mesh without faces or a
// script that cannot be read; UsageError when no window or OpenGL 3.3 context can be opened (no display).
int run_viewer(const ViewerOptions& options);

}  // namespace msd::view
