#include <catch2/catch.hpp>

#include <string>

#include "msdeform/core/errors.h"
#include "msdeform/core/scenes.h"
#include "msdeform/reconstruction/catalogue.h"

#ifdef MSD_HAVE_CHOLMOD
#include <cholmod.h>

using namespace msd;

namespace {
void* no_memory(size_t) { return nullptr; }
// CHOLMOD's allocations fail while it lives (restored also when a check throws).
struct CholmodOutOfMemory {
  void* (*saved)(size_t) = SuiteSparse_config.malloc_func;
  CholmodOutOfMemory() { SuiteSparse_config.malloc_func = &no_memory; }
  ~CholmodOutOfMemory() { SuiteSparse_config.malloc_func = saved; }
};
}  // namespace

TEST_CASE("a factorisation out of memory is reported as such by every method and never as a singular system",
          "[deformation][solver]") {
  SceneOptions options;
  options.resolution = 2000;
  const Scene scene = make_scene("lift", options);
  for (const std::string& name : builtin_methods().names()) {
    INFO(name);
    const auto deformer = builtin_methods().make(name);
    std::string message;
    {
      CholmodOutOfMemory fail;
      try {
        deformer->prepare(scene.P, scene.F, scene.region);
      } catch (const Error& e) {
        message = e.what();
      }
    }
    INFO(message);
    if (message.empty()) continue;  // a method without a sparse factorisation
    CHECK(message.find("out of memory") != std::string::npos);
    CHECK(message.find("singular") == std::string::npos);
  }
}
#endif
