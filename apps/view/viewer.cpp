#include "apps/view/viewer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <map>
#include <memory>
#include <mutex>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>
#include <imgui.h>
#include <imgui_stdlib.h>

#include "apps/view/interaction.h"
#include "msdeform/analysis/metrics.h"
#include "msdeform/analysis/render.h"
#include "msdeform/core/errors.h"
#include "msdeform/core/mesh.h"
#include "msdeform/core/atomic_file.h"
#include "msdeform/core/mesh_io.h"
#include "msdeform/core/rotation.h"

namespace msd::view {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

// The rows of X (#V×3) one after the other in single precision, as OpenGL's vertex buffers take them.
void rows_as_floats(const Positions& X, std::vector<float>& out) {
  out.resize(static_cast<size_t>(X.size()));
  for (Eigen::Index v = 0; v < X.rows(); ++v)
    for (int k = 0; k < 3; ++k) out[3 * v + k] = static_cast<float>(X(v, k));
}

constexpr int kPanelWidth = 380;
constexpr double kIdleBudgetMs = 150;  // how long a nonlinear method iterates per drawn frame while idle

const char* kVertexShader = R"(#version 330 core
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec3 color;
uniform mat4 view;
uniform mat4 projection;
out vec3 view_position;
out vec3 view_normal;
out vec3 vertex_color;
void main() {
  vec4 p = view * vec4(position, 1.0);
  view_position = p.xyz;
  view_normal = mat3(view) * normal;
  vertex_color = color;
  gl_Position = projection * p;
})";

// A head light with a little specular; flat shading takes the face normal from the screen derivatives.
const char* kFragmentShader = R"(#version 330 core
in vec3 view_position;
in vec3 view_normal;
in vec3 vertex_color;
uniform int flat_shading;
out vec4 fragment;
void main() {
  vec3 n = flat_shading != 0 ? normalize(cross(dFdx(view_position), dFdy(view_position))) : normalize(view_normal);
  vec3 to_eye = normalize(-view_position);
  if (dot(n, to_eye) < 0.0) n = -n;  // both sides lit
  vec3 light = normalize(vec3(0.3, 0.5, 1.0));
  float diffuse = max(dot(n, light), 0.0);
  float specular = pow(max(dot(reflect(-light, n), to_eye), 0.0), 40.0);
  fragment = vec4(vertex_color * (0.28 + 0.72 * diffuse) + vec3(0.12 * specular), 1.0);
})";

GLuint compile(GLenum kind, const char* source) {
  const GLuint shader = glCreateShader(kind);
  glShaderSource(shader, 1, &source, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048];
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    throw UsageError(std::string("view: the OpenGL driver did not compile a shader: ") + log);
  }
  return shader;
}

enum class Tool { Orbit, Translate, Rotate, Brush, Lasso };
enum class Coloring { Region, Rigidity, Detail, None };

class Viewer {
 public:
  explicit Viewer(const ViewerOptions& options);
  ~Viewer();
  int run();

 private:
  // --- editing state ---
  void set_mesh(EditCase edit);
  void region_changed();  // renumbers handles, resizes transforms, re-prepares
  Mat4 shown_pose(int code, const std::vector<int>& codes) const;
  void prepare(bool wait);         // starts preparing on a worker thread (wait: until it is done)
  void finish_prepare(bool wait);  // installs the prepared method once the worker is done
  // One frame of the method; iterative methods run at most iteration_limit iterations.
  void frame(int iteration_limit);
  void frame() { frame(options_.iterations_per_frame); }
  void set_iteration_limit(int limit);
  int full_iteration_limit() const {  // --iterations: the longest run of a nonlinear method
    return method_ == "primo" ? options_.settings.primo.max_iterations : options_.settings.arap.max_iterations;
  }
  void iterate_while_idle();
  void recolor();
  bool metric_colors() const { return coloring_ == Coloring::Rigidity || coloring_ == Coloring::Detail; }
  GizmoMode gizmo_mode() const { return tool_ == Tool::Rotate ? GizmoMode::Rotate : GizmoMode::Translate; }
  Vec3 handle_center(int k) const;
  Gizmo gizmo() const;
  void paint_role(const std::vector<int>& vertices);

  // --- input, in pixels of the 3D view ---
  void pointer_down(int button, const Vec2& p, bool shift);
  void pointer_move(const Vec2& p);
  void pointer_up();
  void poll_mouse();

  // --- drawing ---
  void draw_scene();
  void draw_overlay();
  void draw_panel();
  void upload_positions();
  void upload_colors();
  void upload_buffer(int buffer);  // upload_ into buffers_[buffer]
  DepthImage read_depth();
  void write_screenshot(const std::string& path);
  // Before writing a file: the extension of its kind (".png", ".sel", ".def", or "mesh"), writable, not
  // read-only, and none of the files the viewer read. \throw InvalidInput naming the path.
  void check_output(const std::string& path, const std::string& kind) const;
  void write_window_screenshot(const std::string& path);
  void write_pixels_png(const std::string& path, int x0, int width, int height);  // the framebuffer's columns x0..
  void save_result(const std::string& path) {
    check_output(path, "mesh");
    save_mesh(X_, edit_.F, path);
  }
  void save_region(const std::string& path) {
    check_output(path, ".sel");
    write_sel(edit_.region, path);
  }
  void save_transforms(const std::string& path) {
    if (transforms_.empty()) throw InvalidInput(path + ": there is no handle, so no transform to save");
    check_output(path, ".def");
    write_def(transforms_, path);
  }

  // --- scripted mode ---
  bool step_script();  // one step of the current command; false when the script is done
  void run_command_step(const ScriptCommand& c, int step, bool& done);

  void status(const std::string& text) {
    status_ = text;
    if (deformer_ || edit_.region.num_handles() == 0) error_.clear();  // a success replaces an old error
    if (!options_.script.empty() && !options_.quiet) std::printf("view: %s\n", text.c_str());
  }

  ViewerOptions options_;
  EditCase edit_;
  Positions X_;  // the shown positions (#V×3)
  std::vector<Mat4> transforms_;
  int active_handle_ = 0;
  std::string method_;
  std::unique_ptr<Deformer> deformer_;
  struct Preparation {
    std::unique_ptr<Deformer> deformer;
    std::string error;
    double ms = 0;
  };
  struct Phase {  // the phase a preparing method last reported (set on the worker thread)
    std::mutex mutex;
    std::string text;
  };
  std::future<Preparation> preparing_;
  std::shared_ptr<Phase> phase_ = std::make_shared<Phase>();
  Clock::time_point preparing_since_;
  bool needs_prepare_ = true, needs_frame_ = true, iterating_ = false;
  double prepare_ms_ = 0, frame_ms_ = 0, draw_ms_ = 0;
  std::string status_, error_;
  std::unique_ptr<RigidityMetric> rigidity_;
  std::unique_ptr<DetailDistortionMetric> detail_;
  Eigen::VectorXd metric_;
  std::string metric_text_;

  Tool tool_ = Tool::Translate;
  int paint_code_ = Region::kFirstHandle;  // the role painted: 0 fixed, 1 free, 2 + k handle k
  float brush_radius_ = 25;
  Coloring coloring_ = Coloring::Region;
  bool flat_shading_ = false;

  OrbitCamera camera_;
  // a drag in progress
  int drag_button_ = -1;
  Vec2 drag_from_, drag_last_;
  GizmoPart drag_part_ = GizmoPart::None;
  Gizmo drag_gizmo_;
  Mat4 drag_start_transform_ = Mat4::Identity();
  bool drag_pan_ = false;
  Positions stroke_screen_;
  DepthImage stroke_depth_;
  std::vector<Vec2> lasso_;
  Vec2 cursor_ = Vec2(-1, -1);

  // file fields of the panel
  std::string mesh_path_, sel_path_ = "region.sel", def_path_ = "handles.def", out_path_ = "deformed.off",
                          shot_path_ = "view.png";

  // scripted mode
  std::vector<ScriptCommand> script_;
  size_t script_index_ = 0;
  int script_step_ = 0;
  bool script_failed_ = false;
  std::vector<double> command_frame_ms_;
  std::string window_shot_;  // written after the next drawn frame

  // window and OpenGL objects
  GLFWwindow* window_ = nullptr;
  GLuint program_ = 0, vao_ = 0, buffers_[4] = {0, 0, 0, 0};
  std::vector<float> upload_;
  VertexNormals normals_;
  Positions N_;
};

Viewer::Viewer(const ViewerOptions& options) : options_(options), method_(options.method) {
  if (!options_.script.empty()) script_ = read_script(options_.script);  // before a window opens
  for (const ScriptCommand& c : script_) {
    try {
      if (c.verb == "method") builtin_methods().find(c.args[0]);
      if (c.verb == "save-mesh") check_output(c.args[0], "mesh");
      if (c.verb == "save-sel") check_output(c.args[0], ".sel");
      if (c.verb == "save-def") check_output(c.args[0], ".def");
      if (c.verb == "screenshot") check_output(c.args[0], ".png");
    } catch (const Error& e) {
      throw InvalidInput(options_.script + ":" + std::to_string(c.line) + ": " + e.what());
    }
  }
  if (!glfwInit()) throw UsageError("view: GLFW could not start (is there a display? run under xvfb-run without one)");
  glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
  glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
  glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
  glfwWindowHint(GLFW_SAMPLES, 4);
  window_ = glfwCreateWindow(options_.width, options_.height, "msdeform view", nullptr, nullptr);
  if (!window_) {
    glfwTerminate();
    throw UsageError("view: no window with an OpenGL 3.3 core context could be opened (no display, or a driver "
                     "without OpenGL 3.3; Mesa's software renderer has it: LIBGL_ALWAYS_SOFTWARE=1)");
  }
  glfwMakeContextCurrent(window_);
  glfwSwapInterval(1);
  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini written next to the user's files
  ImGui::StyleColorsLight();
  ImGui_ImplGlfw_InitForOpenGL(window_, true);
  ImGui_ImplOpenGL3_Init("#version 330");

  program_ = glCreateProgram();
  const GLuint vs = compile(GL_VERTEX_SHADER, kVertexShader), fs = compile(GL_FRAGMENT_SHADER, kFragmentShader);
  glAttachShader(program_, vs);
  glAttachShader(program_, fs);
  glLinkProgram(program_);
  glDeleteShader(vs);
  glDeleteShader(fs);
  glGenVertexArrays(1, &vao_);
  glGenBuffers(4, buffers_);
  glBindVertexArray(vao_);
  for (GLuint a = 0; a < 3; ++a) {
    glBindBuffer(GL_ARRAY_BUFFER, buffers_[a]);
    glEnableVertexAttribArray(a);
    glVertexAttribPointer(a, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
  }
  glBindVertexArray(0);
  set_mesh(options_.edit);
}

Viewer::~Viewer() {
  glDeleteBuffers(4, buffers_);
  glDeleteVertexArrays(1, &vao_);
  glDeleteProgram(program_);
  ImGui_ImplOpenGL3_Shutdown();
  ImGui_ImplGlfw_Shutdown();
  ImGui::DestroyContext();
  glfwDestroyWindow(window_);
  glfwTerminate();
}

// ---------------------------------------------------------------------------------------------------
// Editing

void Viewer::set_mesh(EditCase edit) {
  if (edit.F.rows() == 0) throw InvalidInput("view: " + edit.name + " has no faces (the viewer draws triangle meshes)");
  if (edit.region.num_vertices() > 0) edit.region.validate(static_cast<int>(edit.P.rows()));  // e.g. handle codes with gaps
  edit_ = std::move(edit);
  mesh_path_ = edit_.path;
  X_ = edit_.P;
  if (edit_.region.num_vertices() != edit_.P.rows()) edit_.region = Region(static_cast<int>(edit_.P.rows()));
  transforms_ = edit_.transforms;
  normals_ = VertexNormals(edit_.F, static_cast<int>(edit_.P.rows()));
  rigidity_ = std::make_unique<RigidityMetric>(edit_.P, edit_.F);
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  camera_.frame(edit_.P, options_.up, options_.view_direction, std::max(w - kPanelWidth, 1), std::max(h, 1));
  // Topology and index buffer once per mesh.
  std::vector<unsigned> indices(edit_.F.size());
  for (Eigen::Index f = 0; f < edit_.F.rows(); ++f)
    for (int k = 0; k < 3; ++k) indices[3 * f + k] = static_cast<unsigned>(edit_.F(f, k));
  glBindVertexArray(vao_);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, buffers_[3]);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, indices.size() * sizeof(unsigned), indices.data(), GL_STATIC_DRAW);
  glBindVertexArray(0);
  for (GLuint a = 0; a < 3; ++a) {
    glBindBuffer(GL_ARRAY_BUFFER, buffers_[a]);
    glBufferData(GL_ARRAY_BUFFER, edit_.P.size() * sizeof(float), nullptr, GL_DYNAMIC_DRAW);
  }
  region_changed();
  upload_positions();
}

void Viewer::region_changed() {
  // Handles numbered 0..n-1 in order of their old numbers, so a handle painted over entirely disappears.
  std::vector<int> codes = edit_.region.codes();
  std::map<int, int> renumber;
  for (int c : codes)
    if (c >= Region::kFirstHandle) renumber.emplace(c, 0);
  std::vector<Mat4> transforms;
  for (auto& [old_code, new_code] : renumber) {
    const int old_handle = old_code - Region::kFirstHandle;
    new_code = Region::kFirstHandle + static_cast<int>(transforms.size());
    transforms.push_back(old_handle < static_cast<int>(transforms_.size()) ? transforms_[old_handle]
                                                                           : shown_pose(old_code, codes));
  }
  for (int& c : codes)
    if (c >= Region::kFirstHandle) c = renumber[c];
  edit_.region = Region::from_codes(codes);
  transforms_ = transforms;
  active_handle_ = std::clamp(active_handle_, 0, std::max(edit_.region.num_handles() - 1, 0));
  try {
    detail_ = std::make_unique<DetailDistortionMetric>(edit_.P, edit_.F, edit_.region);
  } catch (const Error&) {
    detail_.reset();  // no free vertices: nothing to measure
  }
  needs_prepare_ = true;
  recolor();
}

Mat4 Viewer::shown_pose(int code, const std::vector<int>& codes) const {
  // The rigid motion that best maps the rest positions of the vertices with `code` to where they are shown
  // (Kabsch), so painting a new handle on a deformed shape does not send it back to rest.
  Vec3 rest_centre = Vec3::Zero(), shown_centre = Vec3::Zero();
  int n = 0;
  for (size_t v = 0; v < codes.size(); ++v)
    if (codes[v] == code) {
      rest_centre += edit_.P.row(v).transpose();
      shown_centre += X_.row(v).transpose();
      ++n;
    }
  Mat4 T = Mat4::Identity();
  if (n == 0 || X_.rows() != edit_.P.rows()) return T;
  rest_centre /= n;
  shown_centre /= n;
  Mat3 covariance = Mat3::Zero();
  for (size_t v = 0; v < codes.size(); ++v)
    if (codes[v] == code)
      covariance += (edit_.P.row(v).transpose() - rest_centre) * (X_.row(v).transpose() - shown_centre).transpose();
  const Mat3 R = n >= 3 ? best_rotation(covariance) : Mat3::Identity();
  T.topLeftCorner<3, 3>() = R;
  T.topRightCorner<3, 1>() = shown_centre - R * rest_centre;
  return T;
}

void Viewer::prepare(bool wait) {
  needs_prepare_ = false;
  deformer_.reset();
  error_.clear();
  if (edit_.region.num_handles() == 0) {
    error_ = "no handle yet: choose the Brush or Lasso tool, paint 'handle', then drag it";
    X_ = edit_.P;
    upload_positions();
    return;
  }
  try {
    auto d = builtin_methods().make(method_, options_.settings);  // frames set their own iteration limits
    if (d->traits().domain == DeformerDomain::Surface) require_surface(edit_, method_);
    d->set_progress([phase = phase_](const std::string& line) {
      const std::lock_guard<std::mutex> lock(phase->mutex);
      phase->text = line;
    });
    // On a worker thread, so the window stays alive while a large mesh is factored.
    preparing_since_ = Clock::now();
    preparing_ = std::async(std::launch::async, [d = std::move(d), P = edit_.P, F = edit_.F,
                                                 region = edit_.region]() mutable {
      Preparation r;
      const auto start = Clock::now();
      try {
        d->prepare(P, F, region);
        r.deformer = std::move(d);
      } catch (const Error& e) {
        r.error = e.what();
      } catch (const std::bad_alloc&) {
        r.error = "out of memory while preparing";
      }
      r.ms = ms_since(start);
      return r;
    });
  } catch (const Error& e) {
    error_ = e.what();
    X_ = edit_.P;
    upload_positions();
    return;
  }
  if (wait) finish_prepare(true);
}

void Viewer::finish_prepare(bool wait) {
  if (!preparing_.valid()) return;
  if (!wait && preparing_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  Preparation r = preparing_.get();
  if (needs_prepare_) return;  // the region or method changed meanwhile: a newer preparation follows
  if (!r.deformer) {
    error_ = r.error;
    X_ = edit_.P;
    upload_positions();
    return;
  }
  deformer_ = std::move(r.deformer);
  deformer_->set_progress({});  // frames stay allocation-free
  // An iterative method prepared again (a region painted, another method) goes on from the shape shown.
  if (deformer_->traits().initial_guess && X_.rows() == edit_.P.rows() && X_ != edit_.P) deformer_->set_initial_guess(X_);
  prepare_ms_ = r.ms;
  const auto* ms = dynamic_cast<const MultiscaleDeformer*>(deformer_.get());
  status("prepared " + method_ + " in " + std::to_string(static_cast<int>(prepare_ms_)) + " ms" +
         (ms && ms->decomposition_report().low_pass.reused ? " (the multi-scale base computed before)" : ""));
  for (const std::string& w : deformer_->prepare_warnings()) status("warning: " + w);
  needs_frame_ = true;
}

void Viewer::set_iteration_limit(int limit) {
  if (auto* arap = dynamic_cast<ArapDeformer*>(deformer_.get())) arap->set_max_iterations(limit);
  if (auto* primo = dynamic_cast<PrimoDeformer*>(deformer_.get())) primo->set_max_iterations(limit);
}

void Viewer::frame(int iteration_limit) {
  needs_frame_ = false;
  if (!deformer_) return;
  try {
    set_iteration_limit(iteration_limit);
    const auto start = Clock::now();
    deformer_->deform(transforms_, X_);
    frame_ms_ = ms_since(start);
    command_frame_ms_.push_back(frame_ms_);
    const FrameReport& r = deformer_->frame_report();
    iterating_ = deformer_->traits().solve == DeformerSolve::Iterative && !r.converged;
    upload_positions();
    // A metric map costs more than a frame (detail change fairs S'): drawn when the handle is let go.
    if (metric_colors() && drag_part_ == GizmoPart::None) recolor();
  } catch (const Error& e) {
    error_ = e.what();
    iterating_ = false;
  }
}

void Viewer::iterate_while_idle() {
  // Runs as long as fit in the time budget, measured from the last frame: long runs keep the method's
  // acceleration (ARAP's Anderson history restarts with every frame), short ones keep the window alive.
  const int done = std::max(deformer_ ? deformer_->frame_report().iterations : 1, 1);
  const double per_iteration = std::max(frame_ms_ / done, 1e-3);
  const int limit = std::clamp(static_cast<int>(kIdleBudgetMs / per_iteration), options_.iterations_per_frame,
                               full_iteration_limit());
  frame(limit);
}

void Viewer::recolor() {
  auto plain = [&] { return Positions(RenderOptions{}.base_color.transpose().replicate(edit_.P.rows(), 1)); };
  Positions colors;
  metric_text_.clear();
  if (coloring_ == Coloring::Region) {
    colors = region_colors(edit_.region);
  } else if (coloring_ == Coloring::None) {
    colors = plain();
  } else {
    try {
      if (coloring_ == Coloring::Rigidity) {
        metric_ = rigidity_->measure(X_).per_vertex;
      } else {
        if (!detail_) throw InvalidInput("detail change needs free vertices");
        metric_ = detail_->measure(X_).per_vertex;
      }
      auto [lo, hi] = robust_scalar_range(metric_);
      hi = std::max(hi, lo + 1e-9);  // at rest: round-off, not a pattern to colour
      colors.resize(metric_.size(), 3);
      for (Eigen::Index v = 0; v < metric_.size(); ++v)
        colors.row(v) = viridis((metric_[v] - lo) / std::max(hi - lo, 1e-300)).transpose();
      char text[160];
      std::snprintf(text, sizeof text, "%s: mean %.3g, max %.3g (colours %.3g .. %.3g)",
                    coloring_ == Coloring::Rigidity ? "rigidity" : "detail change", metric_.mean(),
                    metric_.maxCoeff(), lo, hi);
      metric_text_ = text;
    } catch (const Error& e) {
      metric_text_ = e.what();
      colors = plain();
    }
  }
  rows_as_floats(colors, upload_);
  upload_buffer(2);
}

void Viewer::upload_positions() {
  normals_.compute(X_, N_);
  drawing_positions(camera_, X_, upload_);
  upload_buffer(0);
  rows_as_floats(N_, upload_);
  upload_buffer(1);
}

void Viewer::upload_buffer(int buffer) {
  glBindBuffer(GL_ARRAY_BUFFER, buffers_[buffer]);
  glBufferSubData(GL_ARRAY_BUFFER, 0, upload_.size() * sizeof(float), upload_.data());
}

Vec3 Viewer::handle_center(int k) const {
  const std::vector<int> vs = edit_.region.handle_vertices(k);
  Vec3 c = Vec3::Zero();
  for (int v : vs) c += edit_.P.row(v).transpose();
  c /= std::max<double>(vs.size(), 1);
  return transform_point(transforms_.at(k), c);
}

Gizmo Viewer::gizmo() const {
  Gizmo g;
  g.center = handle_center(active_handle_);
  return g;
}

void Viewer::paint_role(const std::vector<int>& vertices) {
  if (vertices.empty()) return;
  Region r = edit_.region;
  if (paint_code_ >= Region::kFirstHandle) {
    r.set_handle(vertices, paint_code_ - Region::kFirstHandle);
  } else if (paint_code_ == Region::kFixed) {
    r.set_fixed(vertices);
  } else {
    r.set_free(vertices);
  }
  edit_.region = r;
  recolor();  // the region is committed when the stroke ends (region_changed)
}

// ---------------------------------------------------------------------------------------------------
// Input

void Viewer::pointer_down(int button, const Vec2& p, bool shift) {
  drag_button_ = button;
  drag_from_ = drag_last_ = p;
  drag_part_ = GizmoPart::None;
  drag_pan_ = button == 2 || (button == 1 && shift);
  if (button != 0) return;
  const bool gizmo_tool = tool_ == Tool::Translate || tool_ == Tool::Rotate;
  if (gizmo_tool && deformer_ && edit_.region.num_handles() > 0) {
    drag_gizmo_ = gizmo();
    drag_part_ = drag_gizmo_.pick(camera_, gizmo_mode(), p);
    drag_start_transform_ = transforms_[active_handle_];
  } else if (tool_ == Tool::Brush || tool_ == Tool::Lasso) {
    stroke_depth_ = read_depth();
    stroke_screen_ = project_vertices(camera_, X_);
    lasso_.assign(1, p);
    if (tool_ == Tool::Brush) paint_role(brush_select(stroke_screen_, p, brush_radius_, stroke_depth_));
  }
}

void Viewer::pointer_move(const Vec2& p) {
  cursor_ = p;
  if (drag_button_ < 0) return;
  const Vec2 d = p - drag_last_;
  drag_last_ = p;
  if (drag_pan_) {
    camera_.pan(d.x(), d.y());
  } else if (drag_button_ == 1 || (drag_button_ == 0 && tool_ == Tool::Orbit) ||
             (drag_button_ == 0 && drag_part_ == GizmoPart::None && (tool_ == Tool::Translate || tool_ == Tool::Rotate))) {
    camera_.orbit(d.x(), d.y());
  } else if (drag_part_ != GizmoPart::None) {
    const GizmoMode mode = gizmo_mode();
    const Mat4 next = drag_gizmo_.drag(camera_, mode, drag_part_, drag_from_, p) * drag_start_transform_;
    // From where the handle is to where the cursor puts it: the turn must not pass half a turn on the way.
    const Mat4& now = transforms_[active_handle_];
    if (mode == GizmoMode::Rotate && !turn_stays_below_half(now, next)) {
      error_ = half_turn_message(active_handle_, now);  // the handle stays where it is
      return;
    }
    transforms_[active_handle_] = next;
    needs_frame_ = true;
  } else if (tool_ == Tool::Brush) {
    paint_role(brush_select(stroke_screen_, p, brush_radius_, stroke_depth_));
  } else if (tool_ == Tool::Lasso && (p - lasso_.back()).norm() >= 3) {
    lasso_.push_back(p);
  }
}

void Viewer::pointer_up() {
  if (drag_button_ == 0 && tool_ == Tool::Lasso) paint_role(lasso_select(stroke_screen_, lasso_, stroke_depth_));
  if (drag_button_ == 0 && (tool_ == Tool::Brush || tool_ == Tool::Lasso)) region_changed();
  const bool moved_handle = drag_part_ != GizmoPart::None;
  lasso_.clear();
  drag_button_ = -1;
  drag_part_ = GizmoPart::None;
  if (moved_handle && metric_colors()) recolor();
}

void Viewer::poll_mouse() {
  const ImGuiIO& io = ImGui::GetIO();
  const Vec2 p(io.MousePos.x - kPanelWidth, io.MousePos.y);
  if (io.WantCaptureMouse && drag_button_ < 0) {
    cursor_ = Vec2(-1, -1);
    return;
  }
  for (int b = 0; b < 3; ++b)
    if (ImGui::IsMouseClicked(b) && drag_button_ < 0 && p.x() >= 0) pointer_down(b, p, io.KeyShift);
  pointer_move(p);
  if (drag_button_ >= 0 && ImGui::IsMouseReleased(drag_button_)) pointer_up();
  if (io.MouseWheel != 0 && p.x() >= 0) camera_.zoom(io.MouseWheel);
}

// ---------------------------------------------------------------------------------------------------
// Drawing

void Viewer::draw_scene() {
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  camera_.resize(std::max(w - kPanelWidth, 1), std::max(h, 1));
  glViewport(0, 0, w, h);
  glClearColor(0.80f, 0.85f, 0.90f, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glViewport(kPanelWidth, 0, camera_.width(), camera_.height());
  glEnable(GL_DEPTH_TEST);
  glUseProgram(program_);
  const Eigen::Matrix4f V = camera_.frame_view_matrix().cast<float>(),
                        Pm = camera_.frame_projection_matrix().cast<float>();
  glUniformMatrix4fv(glGetUniformLocation(program_, "view"), 1, GL_FALSE, V.data());
  glUniformMatrix4fv(glGetUniformLocation(program_, "projection"), 1, GL_FALSE, Pm.data());
  glUniform1i(glGetUniformLocation(program_, "flat_shading"), flat_shading_ ? 1 : 0);
  glBindVertexArray(vao_);
  glDrawElements(GL_TRIANGLES, static_cast<GLsizei>(edit_.F.size()), GL_UNSIGNED_INT, nullptr);
  glBindVertexArray(0);
  glUseProgram(0);
  glDisable(GL_DEPTH_TEST);
  glViewport(0, 0, w, h);
}

// width×height pixels of the framebuffer from column x0, `channels` values each, top row first (OpenGL's
// rows start at the bottom).
template <class T>
std::vector<T> read_pixels(int x0, int width, int height, GLenum format, GLenum type, int channels) {
  const size_t row = static_cast<size_t>(width) * channels;
  std::vector<T> bottom_up(row * height), top_down(row * height);
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(x0, 0, width, height, format, type, bottom_up.data());
  for (int y = 0; y < height; ++y)
    std::copy_n(bottom_up.begin() + static_cast<long>((height - 1 - y) * row), row, top_down.begin() + static_cast<long>(y * row));
  return top_down;
}

DepthImage Viewer::read_depth() {
  draw_scene();  // the depth of what is shown now
  DepthImage d;
  d.width = camera_.width();
  d.height = camera_.height();
  d.depth = read_pixels<float>(kPanelWidth, d.width, d.height, GL_DEPTH_COMPONENT, GL_FLOAT, 1);
  return d;
}

void Viewer::write_pixels_png(const std::string& path, int x0, int width, int height) {
  Image image(width, height);
  image.rgb = read_pixels<std::uint8_t>(x0, width, height, GL_RGB, GL_UNSIGNED_BYTE, 3);
  write_png(image, path);
}

void Viewer::write_screenshot(const std::string& path) {
  check_output(path, ".png");
  draw_scene();
  write_pixels_png(path, kPanelWidth, camera_.width(), camera_.height());
}

void Viewer::check_output(const std::string& path, const std::string& kind) const {
  if (kind == "mesh")
    check_mesh_format(path, "view");
  else if (file_extension(path) != kind)
    throw InvalidInput(path + ": this file is written in the " + kind + " format; name it NAME" + kind);
  check_writable(path, "view");
  std::vector<std::string> inputs = options_.inputs;
  inputs.push_back(edit_.path);
  for (const std::string& input : inputs)
    if (!input.empty() && same_file(path, input))
      throw InvalidInput(path + " is one of the files the viewer read; it is not replaced (save under another name)");
}

void Viewer::write_window_screenshot(const std::string& path) {
  check_output(path, ".png");
  int w = 0, h = 0;
  glfwGetFramebufferSize(window_, &w, &h);
  write_pixels_png(path, 0, w, h);
}

void Viewer::draw_overlay() {
  ImDrawList* draw = ImGui::GetForegroundDrawList();
  const ImVec2 offset(kPanelWidth, 0);
  auto at = [&](const Vec3& screen) { return ImVec2(offset.x + screen.x(), offset.y + screen.y()); };
  if ((tool_ == Tool::Translate || tool_ == Tool::Rotate) && deformer_ && edit_.region.num_handles() > 0) {
    const Gizmo g = drag_part_ != GizmoPart::None ? drag_gizmo_ : gizmo();
    const ImVec2 c = at(camera_.project(g.center));
    const ImU32 colors[3] = {IM_COL32(220, 40, 40, 255), IM_COL32(40, 170, 40, 255), IM_COL32(40, 80, 230, 255)};
    const GizmoMode mode = gizmo_mode();
    const GizmoPart hover = drag_part_ != GizmoPart::None ? drag_part_ : g.pick(camera_, mode, cursor_);
    for (int a = 0; a < 3; ++a) {
      const ImVec2 tip = at(camera_.project(g.arrow_tip(camera_, a)));
      const bool hot = hover == static_cast<GizmoPart>(static_cast<int>(GizmoPart::X) + a);
      draw->AddLine(c, tip, colors[a], hot ? 5.f : 3.f);
      if (tool_ == Tool::Translate)
        draw->AddCircleFilled(tip, hot ? 7.f : 5.f, colors[a]);
      else
        draw->AddCircle(tip, hot ? 9.f : 7.f, colors[a], 16, 2.5f);
    }
    const float radius = mode == GizmoMode::Translate ? 10.f : static_cast<float>(g.ring_pixels());
    draw->AddCircle(c, radius, IM_COL32(30, 30, 30, 255), 48, hover == GizmoPart::Center ? 4.f : 2.f);
  }
  if (tool_ == Tool::Brush && cursor_.x() >= 0)
    draw->AddCircle(ImVec2(offset.x + cursor_.x(), cursor_.y()), brush_radius_, IM_COL32(20, 20, 20, 200), 48, 1.5f);
  if (tool_ == Tool::Lasso && lasso_.size() > 1) {
    std::vector<ImVec2> points;
    for (const Vec2& p : lasso_) points.emplace_back(offset.x + p.x(), p.y());
    draw->AddPolyline(points.data(), static_cast<int>(points.size()), IM_COL32(20, 20, 20, 230), ImDrawFlags_Closed, 1.5f);
  }
}

void Viewer::draw_panel() {
  int w = 0, h = 0;
  glfwGetWindowSize(window_, &w, &h);
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, static_cast<float>(h)));
  ImGui::Begin("msdeform", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::PushItemWidth(-120);
  ImGui::Text("%s: %ld vertices, %ld faces", edit_.name.c_str(), static_cast<long>(edit_.P.rows()),
              static_cast<long>(edit_.F.rows()));
  if (!edit_.surface_problem.empty()) ImGui::TextWrapped("not a manifold mesh: %s", edit_.surface_problem.c_str());

  if (ImGui::CollapsingHeader("Method", ImGuiTreeNodeFlags_DefaultOpen)) {
    if (ImGui::BeginCombo("method", method_.c_str())) {
      for (const MethodEntry& e : builtin_methods().entries())
        if (ImGui::Selectable(e.name.c_str(), e.name == method_)) {
          method_ = e.name;
          needs_prepare_ = true;
        }
      ImGui::EndCombo();
    }
    const MethodEntry& entry = builtin_methods().find(method_);
    ImGui::TextWrapped("%s (seed %s)", entry.summary.c_str(), entry.section.c_str());
    if (method_ == "arap" || method_ == "primo") {
      ImGui::SliderInt("iterations/frame", &options_.iterations_per_frame, 1, 50, "%d", ImGuiSliderFlags_AlwaysClamp);
    }
    if (method_ == "shell" || is_multiscale(method_)) {
      float k = static_cast<float>(options_.settings.shell.ks);
      if (ImGui::SliderFloat("stretching k_s", &k, 0, 10, "%.2f", ImGuiSliderFlags_AlwaysClamp)) {
        options_.settings.shell.ks = k;
        needs_prepare_ = true;
      }
    }
    if (preparing_.valid()) {
      const std::lock_guard<std::mutex> lock(phase_->mutex);
      ImGui::TextWrapped("preparing %s (%.1f s) %s", method_.c_str(), ms_since(preparing_since_) / 1000,
                         phase_->text.c_str());
    }
    ImGui::Text("prepare %.1f ms, frame %.2f ms, draw %.1f ms", prepare_ms_, frame_ms_, draw_ms_);
    if (deformer_) {
      const FrameReport& r = deformer_->frame_report();
      if (deformer_->traits().solve == DeformerSolve::Iterative)
        ImGui::Text("%s: %d iterations, residual %.2g", iterating_ ? "iterating" : "converged", r.iterations, r.residual);
      if (r.folded_faces >= 0) ImGui::Text("folded faces: %d", r.folded_faces);
      for (const std::string& warning : r.warnings)
        if (!iterating_) ImGui::TextWrapped("warning: %s", warning.c_str());
    }
    if (!error_.empty()) {
      ImGui::PushStyleColor(ImGuiCol_Text, ImVec4(0.75f, 0.05f, 0.05f, 1));
      ImGui::TextWrapped("%s", error_.c_str());
      ImGui::PopStyleColor();
    }
  }

  if (ImGui::CollapsingHeader("Tool", ImGuiTreeNodeFlags_DefaultOpen)) {
    int t = static_cast<int>(tool_);
    const char* tools[] = {"orbit", "move", "rotate", "brush", "lasso"};
    for (int i = 0; i < 5; ++i) {
      if (i % 3) ImGui::SameLine();
      ImGui::RadioButton(tools[i], &t, i);
    }
    tool_ = static_cast<Tool>(t);
    ImGui::TextWrapped("left drag: the tool (move/rotate: the gizmo's arrows or centre); right drag: orbit; middle "
                       "or shift+right: pan; wheel: zoom");
    const int handles = edit_.region.num_handles();
    if (handles > 0) ImGui::SliderInt("active handle", &active_handle_, 0, handles - 1);
    std::vector<std::string> roles = {"fixed", "free"};
    for (int k = 0; k <= handles; ++k) roles.push_back(k < handles ? "handle " + std::to_string(k) : "new handle");
    const int role = std::min(paint_code_, static_cast<int>(roles.size()) - 1);
    if (ImGui::BeginCombo("paints", roles[role].c_str())) {
      for (int i = 0; i < static_cast<int>(roles.size()); ++i)
        if (ImGui::Selectable(roles[i].c_str(), i == role)) paint_code_ = i;
      ImGui::EndCombo();
    }
    ImGui::SliderFloat("brush radius", &brush_radius_, 2, 200, "%.0f px", ImGuiSliderFlags_AlwaysClamp);
    if (ImGui::Button("reset handles")) {
      std::fill(transforms_.begin(), transforms_.end(), Mat4::Identity());
      needs_frame_ = true;
    }
    ImGui::SameLine();
    if (ImGui::Button("clear region")) {
      edit_.region = Region(static_cast<int>(edit_.P.rows()));
      region_changed();
    }
  }

  if (ImGui::CollapsingHeader("Display", ImGuiTreeNodeFlags_DefaultOpen)) {
    int c = static_cast<int>(coloring_);
    const char* colorings[] = {"region", "rigidity", "detail change", "none"};
    if (ImGui::Combo("colour", &c, colorings, 4)) {
      coloring_ = static_cast<Coloring>(c);
      recolor();
    }
    if (!metric_text_.empty()) ImGui::TextWrapped("%s", metric_text_.c_str());
    ImGui::Checkbox("flat shading", &flat_shading_);
    ImGui::SameLine();
    if (ImGui::Button("reset view")) {
      camera_.frame(edit_.P, options_.up, options_.view_direction, camera_.width(), camera_.height());
    }
  }

  if (ImGui::CollapsingHeader("Files")) {
    auto row = [&](const char* label, std::string& path, const char* button) {
      ImGui::PushID(label);
      ImGui::InputText(label, &path);
      ImGui::SameLine();
      const bool pressed = ImGui::Button(button);
      ImGui::PopID();
      return pressed;
    };
    try {
      if (row("mesh", mesh_path_, "load")) {
        EditCase c = load_edit_case(mesh_path_);
        set_mesh(std::move(c));
        status("loaded " + mesh_path_);
      }
      if (row("result", out_path_, "save")) {
        save_result(out_path_);
        status("saved " + out_path_);
      }
      if (row(".sel", sel_path_, "save")) {
        save_region(sel_path_);
        status("saved " + sel_path_);
      }
      if (ImGui::Button("load .sel")) {
        Region r = read_sel(sel_path_, static_cast<int>(edit_.P.rows()));
        r.validate(static_cast<int>(edit_.P.rows()));
        edit_.region = r;
        region_changed();
        status("loaded " + sel_path_);
      }
      if (row(".def", def_path_, "save")) {
        save_transforms(def_path_);
        status("saved " + def_path_);
      }
      if (ImGui::Button("load .def")) {
        std::vector<Mat4> t = read_def(def_path_);
        if (static_cast<int>(t.size()) != edit_.region.num_handles())
          throw InvalidInput(def_path_ + " has " + std::to_string(t.size()) + " transforms for " +
                             std::to_string(edit_.region.num_handles()) + " handles");
        transforms_ = t;
        needs_frame_ = true;
        status("loaded " + def_path_);
      }
      if (row("screenshot", shot_path_, "save")) {
        write_screenshot(shot_path_);
        status("saved " + shot_path_);
      }
    } catch (const Error& e) {
      error_ = e.what();
    }
  }
  if (!status_.empty()) ImGui::TextWrapped("%s", status_.c_str());
  ImGui::PopItemWidth();
  ImGui::End();
}

// ---------------------------------------------------------------------------------------------------
// Scripted mode

void Viewer::run_command_step(const ScriptCommand& c, int step, bool& done) {
  const std::string& path = options_.script;
  auto number = [&](size_t i) { return script_number(c, i, path); };
  auto steps_arg = [&](size_t i) {
    if (c.args.size() <= i) return 10;
    const double s = number(i);
    if (s < 1 || s > 10000 || s != std::floor(s)) throw InvalidInput("STEPS is a whole number from 1 to 10000");
    return static_cast<int>(s);
  };
  auto need_handle = [&] {
    if (edit_.region.num_handles() == 0) throw InvalidInput("there is no handle to move");
    if (!deformer_) throw InvalidInput("the method is not prepared: " + error_);
  };
  done = true;
  const std::string& v = c.verb;
  if (v == "method") {
    builtin_methods().find(c.args[0]);  // throws, listing the known names
    method_ = c.args[0];
    prepare(/*wait=*/true);
    if (!deformer_ && edit_.region.num_handles() > 0) throw InvalidInput(error_);
  } else if (v == "handle") {
    const int k = static_cast<int>(number(0));
    if (k < 0 || k >= edit_.region.num_handles())
      throw InvalidInput("handle " + std::to_string(k) + " does not exist (" +
                         std::to_string(edit_.region.num_handles()) + " handles)");
    active_handle_ = k;
  } else if (v == "translate" || v == "rotate") {
    need_handle();
    const int steps = steps_arg(v == "translate" ? 3 : 4);
    Mat4 T = Mat4::Identity();
    if (v == "translate") {
      T.topRightCorner<3, 1>() = Vec3(number(0), number(1), number(2)) / steps;
    } else {
      const Vec3 axis(number(0), number(1), number(2));
      if (axis.norm() == 0) throw InvalidInput("the rotation axis is zero");
      const Vec3 c0 = handle_center(active_handle_);
      const Eigen::Matrix3d R = Eigen::AngleAxisd(number(3) * 3.14159265358979323846 / 180 / steps, axis.normalized()).toRotationMatrix();
      T.topLeftCorner<3, 3>() = R;
      T.topRightCorner<3, 1>() = c0 - R * c0;
      if (!turn_stays_below_half(transforms_[active_handle_], T * transforms_[active_handle_]))
        throw InvalidInput(half_turn_message(active_handle_, transforms_[active_handle_]));
    }
    transforms_[active_handle_] = T * transforms_[active_handle_];
    needs_frame_ = true;
    done = step + 1 >= steps;
  } else if (v == "gizmo") {
    need_handle();
    const int steps = steps_arg(4);
    tool_ = c.args[0] == "rotate" ? Tool::Rotate : Tool::Translate;
    const Gizmo g = step == 0 ? gizmo() : drag_gizmo_;
    const Vec2 center = camera_.project(g.center).head<2>();
    Vec2 start = center;
    if (c.args[1] != "center") {
      const int axis = c.args[1] == "x" ? 0 : c.args[1] == "y" ? 1 : 2;
      start = center + 0.7 * (camera_.project(g.arrow_tip(camera_, axis)).head<2>() - center);
    }
    if (c.args[1] == "center" && tool_ == Tool::Rotate) start = center + Vec2(g.ring_pixels(), 0);  // on the ring
    if (step == 0) {
      if (start.x() < 0 || start.y() < 0 || start.x() >= camera_.width() || start.y() >= camera_.height())
        throw InvalidInput("the gizmo is outside the 3D view (orbit, pan or zoom to bring it in)");
      pointer_down(0, start, false);
      if (drag_part_ == GizmoPart::None) throw InvalidInput("the gizmo part is not under the cursor");
      done = false;
      return;
    }
    pointer_move(start + (static_cast<double>(step) / steps) * Vec2(number(2), number(3)));
    if (step >= steps) {
      pointer_up();
      return;
    }
    done = false;
  } else if (v == "orbit") {
    camera_.orbit(number(0), number(1));
  } else if (v == "zoom") {
    camera_.zoom(number(0));
  } else if (v == "paint" || v == "lasso") {
    const bool handle = c.args[0] == "handle";
    const size_t first = handle ? 2 : 1;
    if (handle) {
      const int k = static_cast<int>(number(1));
      if (k < 0 || k > edit_.region.num_handles())
        throw InvalidInput("handle " + std::to_string(k) + ": the next new handle is " +
                           std::to_string(edit_.region.num_handles()));
      paint_code_ = Region::kFirstHandle + k;
    } else {
      paint_code_ = c.args[0] == "fixed" ? Region::kFixed : Region::kFree;
    }
    const int before = static_cast<int>(std::count(edit_.region.codes().begin(), edit_.region.codes().end(), paint_code_));
    if (v == "paint") {
      tool_ = Tool::Brush;
      brush_radius_ = static_cast<float>(number(first + 2));
      pointer_down(0, Vec2(number(first), number(first + 1)), false);
    } else {
      tool_ = Tool::Lasso;
      pointer_down(0, Vec2(number(first), number(first + 1)), false);
      for (size_t i = first + 2; i + 1 < c.args.size(); i += 2) pointer_move(Vec2(number(i), number(i + 1)));
    }
    pointer_up();
    const int after = static_cast<int>(std::count(edit_.region.codes().begin(), edit_.region.codes().end(), paint_code_));
    status("line " + std::to_string(c.line) + ": " + v + " " + c.args[0] + ": " + std::to_string(after) +
           " vertices have that role (" + std::to_string(after - before) + " more)");
  } else if (v == "color") {
    coloring_ = c.args[0] == "region"     ? Coloring::Region
                : c.args[0] == "rigidity" ? Coloring::Rigidity
                : c.args[0] == "detail"   ? Coloring::Detail
                                          : Coloring::None;
    recolor();
  } else if (v == "shading") {
    flat_shading_ = c.args[0] == "flat";
  } else if (v == "converge") {
    if (needs_prepare_) prepare(/*wait=*/true);
    const auto start = Clock::now();
    do frame(full_iteration_limit());
    while (iterating_ && ms_since(start) < 10000);
    if (iterating_) throw InvalidInput("no convergence within 10 s");
  } else if (v == "screenshot") {
    if (needs_prepare_) prepare(/*wait=*/true);
    if (needs_frame_) frame();
    if (c.args.size() == 2)
      window_shot_ = c.args[0];
    else
      write_screenshot(c.args[0]);
  } else if (v == "save-mesh") {
    save_result(c.args[0]);
  } else if (v == "save-sel") {
    save_region(c.args[0]);
  } else if (v == "save-def") {
    save_transforms(c.args[0]);
  } else if (v == "reset") {
    std::fill(transforms_.begin(), transforms_.end(), Mat4::Identity());
    needs_frame_ = true;
  }
}

bool Viewer::step_script() {
  if (script_index_ >= script_.size() || script_failed_) return false;
  const ScriptCommand& c = script_[script_index_];
  if (script_step_ == 0) command_frame_ms_.clear();
  bool done = true;
  try {
    if (needs_prepare_)
      prepare(/*wait=*/true);
    else
      finish_prepare(/*wait=*/true);  // one the window's loop started
    if (!deformer_ && edit_.region.num_handles() > 0) throw InvalidInput("the method could not be prepared: " + error_);
    if (needs_frame_) frame();  // the shape shown (e.g. posed by --def) before the command runs
    run_command_step(c, script_step_, done);
    if (needs_frame_) frame();
  } catch (const Error& e) {
    std::fprintf(stderr, "view: %s:%d: %s: %s\n", options_.script.c_str(), c.line, c.verb.c_str(), e.what());
    script_failed_ = true;
    return false;
  }
  if (!error_.empty() && (c.verb == "translate" || c.verb == "rotate" || c.verb == "gizmo")) {
    std::fprintf(stderr, "view: %s:%d: %s: %s\n", options_.script.c_str(), c.line, c.verb.c_str(), error_.c_str());
    script_failed_ = true;
    return false;
  }
  ++script_step_;
  if (!done) return true;
  if (!options_.quiet) {
    std::string line = "line " + std::to_string(c.line) + ": " + c.verb;
    for (const std::string& a : c.args) line += " " + a;
    if (!command_frame_ms_.empty()) {
      std::vector<double> t = command_frame_ms_;
      std::sort(t.begin(), t.end());
      char text[200];
      std::snprintf(text, sizeof text, " (%zu frames of %s: median %.2f ms, max %.2f ms; draw %.1f ms)", t.size(),
                    method_.c_str(), t[t.size() / 2], t.back(), draw_ms_);
      line += text;
      if (deformer_ && deformer_->frame_report().folded_faces > 0)
        line += "; folded faces " + std::to_string(deformer_->frame_report().folded_faces);
      if (deformer_ && !iterating_)
        for (const std::string& w : deformer_->frame_report().warnings) line += "\n  warning: " + w;
    }
    std::printf("view: %s\n", line.c_str());
    std::fflush(stdout);
  }
  ++script_index_;
  script_step_ = 0;
  return true;
}

int Viewer::run() {
  bool scripted = !script_.empty();
  while (!glfwWindowShouldClose(window_)) {
    if (scripted || iterating_ || needs_frame_ || needs_prepare_ || preparing_.valid())
      glfwPollEvents();
    else
      glfwWaitEvents();  // nothing to do until the user acts
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    if (scripted) {
      scripted = step_script();
      if (script_failed_) break;  // no --screenshot of a half-done script
    } else {
      poll_mouse();
    }
    finish_prepare(/*wait=*/false);
    if (needs_prepare_ && !preparing_.valid()) prepare(/*wait=*/false);
    const bool dragging = drag_part_ != GizmoPart::None;
    if (needs_frame_) {
      frame();
    } else if (iterating_ && !dragging && !scripted) {  // scripts iterate only when told (converge)
      iterate_while_idle();
    }
    if (!scripted && !options_.screenshot.empty()) {
      finish_prepare(/*wait=*/true);
      if (needs_frame_) frame();
      if (!error_.empty() && edit_.region.num_handles() > 0) {
        std::fprintf(stderr, "view: %s\n", error_.c_str());
        return 1;
      }
      write_screenshot(options_.screenshot);
      std::printf("view: wrote %s\n", options_.screenshot.c_str());
      break;
    }
    draw_panel();
    draw_overlay();
    const auto start = Clock::now();
    draw_scene();
    ImGui::Render();
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    if (!window_shot_.empty()) {
      write_window_screenshot(window_shot_);
      window_shot_.clear();
    }
    glfwSwapBuffers(window_);
    draw_ms_ = ms_since(start);
  }
  return script_failed_ ? 1 : 0;
}

}  // namespace

int run_viewer(const ViewerOptions& options) {
  if (options.edit.F.rows() == 0)
    throw InvalidInput("view: " + options.edit.name + " has no faces (the viewer draws triangle meshes)");
  Viewer viewer(options);
  return viewer.run();
}

}  // namespace msd::view
