#pragma once
// Golden metric tables of the regression suites: one row per (scene, method, metric). Re-record with
// MSD_UPDATE_GOLDEN=1 and explain the change in the commit that updates the file.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "apps/compare/runner.h"
#include "msdeform/core/atomic_file.h"

namespace msd::test {

//! The compared metrics of a result, by column name.
inline std::map<std::string, double> golden_metrics(const MethodResult& r) {
  return {{"rigidity_mean", r.rigidity.mean},     {"rigidity_p95", r.rigidity.p95},
          {"distortion_mean", r.distortion.mean}, {"distortion_p95", r.distortion.p95},
          {"self_intersections", double(r.self_intersections)}};
}

//! The result of `method` on `scene`; fails the test when there is none.
inline const MethodResult& find_result(const std::vector<MethodResult>& results, const std::string& scene,
                                       const std::string& method) {
  for (const auto& r : results)
    if (r.scene == scene && r.method == method) return r;
  FAIL("no result for " << scene << " / " << method);
  throw;
}

//! Compares every ok result with the table at `path` (rigidity and distortion within 3 %, self-intersection
//! counts within max(3, 5 %): counts near contact can flip), or re-records it under MSD_UPDATE_GOLDEN.
inline void check_golden(const std::string& path, const std::vector<MethodResult>& results) {
  if (std::getenv("MSD_UPDATE_GOLDEN")) {
    std::string csv = "scene,method,metric,value\n";
    for (const auto& r : results)
      if (r.ok)
        for (const auto& [name, value] : golden_metrics(r)) {
          std::ostringstream line;
          line.precision(10);
          line << r.scene << ',' << r.method << ',' << name << ',' << value << '\n';
          csv += line.str();
        }
    write_file_atomically(path, csv);
    WARN("re-recorded " << path);
    return;
  }
  std::ifstream in(path);
  REQUIRE(in.good());
  std::string line;
  std::getline(in, line);  // header
  size_t compared = 0, ok = 0;
  while (std::getline(in, line)) {
    std::istringstream cells(line);
    std::string scene, method, metric, value;
    std::getline(cells, scene, ',');
    std::getline(cells, method, ',');
    std::getline(cells, metric, ',');
    std::getline(cells, value, ',');
    const MethodResult& r = find_result(results, scene, method);
    INFO(scene << " / " << method << ": " << r.error);
    REQUIRE(r.ok);
    const double golden = std::stod(value), now = golden_metrics(r).at(metric);
    INFO(scene << " / " << method << " / " << metric << ": golden " << golden << ", now " << now);
    if (metric == "self_intersections")
      CHECK(std::abs(now - golden) <= std::max(3.0, 0.05 * golden));
    else
      CHECK(std::abs(now - golden) <= 0.03 * std::abs(golden) + 1e-4);
    ++compared;
  }
  for (const auto& r : results) ok += r.ok;
  CHECK(compared == ok * golden_metrics(MethodResult{}).size());
}

}  // namespace msd::test
