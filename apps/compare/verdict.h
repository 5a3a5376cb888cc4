#pragma once
//! \file What the comparison says about each result, in words: a verdict per method and edit from
//! measured thresholds (the seed's Fig. 9.16 question "which method suits which edit, and why"), the best
//! result of each edit, and the page's inline SVG charts. Part of msd::compare.

#include <string>
#include <vector>

#include "apps/compare/runner.h"

namespace msd {

enum class Verdict { Good, Fair, Poor, Broken, NotJudged, Failed };
//! "good", "fair", "poor", "broken", "not-judged", "failed" (also the page's CSS classes)
const char* to_string(Verdict v);

//! Thresholds of the verdicts. Rigidity (one-ring rotation residual) is judged against the most rigid
//! result of the same edit, detail distortion (|Δh| over the largest detail height) absolutely.
struct VerdictThresholds {
  double fair_rigidity = 2, poor_rigidity = 4;         //!< × the edit's best rigidity
  //! Rigidity means below this are rigid whatever the ratios (a uniform 0.1 % stretch reads 1e-6; a rigid
  //! motion reads 1e-31 to 1e-22 from rounding): ratios are taken against at least this.
  double rigid_floor = 1e-6;
  double fair_distortion = 0.10, poor_distortion = 0.25;  //!< of the largest detail height
  //! Handles that scale by s allow the details to change by |s − 1| of their height (EditScaling's growth
  //! or shrink); beyond 1 + scale_tolerance the heights, measured against the rest's, are not judged.
  double scale_tolerance = 0.1;
  //! Relative volume change of a closed mesh beyond what the handles ask (EditScaling::volume_excess();
  //! without scaling, |V'/V − 1|): beyond these, fair and poor. On the survey cylinder's 120° bend ARAP loses
  //! 13 %, the shell 51 %; `msdeform deform` warns beyond the poor one (shape_change_warning()).
  double fair_volume = 0.15, poor_volume = 0.30;
  //! A result lost the shape, and is broken, when its rigidity mean is above broken_rigidity (as a uniform
  //! scale by 2 reads) and above broken_rigidity_ratio times the edit's most rigid result, or its volume
  //! factor (V'/V or V/V', closed meshes) is above broken_volume and broken_volume times the edit's smallest,
  //! or beyond broken_volume_alone times the range the handles ask (EditScaling) whatever else ran:
  //! Laplacian editing ballooned the survey cactus to 31 times its volume (rigidity 5.98; the others below
  //! 1.3), while a handle pulled to 4 times its distance from the fixed part stretches every method's
  //! result alike (ARAP 6.5, volume ×4.3).
  double broken_rigidity = 1, broken_rigidity_ratio = 10, broken_volume = 3, broken_volume_alone = 10;
};

struct Assessment {
  Verdict verdict = Verdict::Failed;
  std::string reason;  //!< in words, with the figures, e.g. "rigidity 5.1× the best (the shape shears)"
  bool best = false;   //!< the edit's best result: of the best verdict present, the most rigid, then least distortion
};

//! One assessment per result (same order). Failed: the run threw (the reason is its message). Broken:
//! self-intersecting triangle pairs or triangles folded over a multi-scale base. Poor / fair: rigidity or
//! distortion beyond the thresholds, or a closed mesh's volume changed by an edit that does not scale. Good
//! otherwise, but at most fair when the method warned (e.g. an iterative method that did not converge; the
//! warning is part of the reason). Not judged: neither rigidity nor detail distortion could be measured (a
//! point cloud), never the best.
std::vector<Assessment> assess(const std::vector<MethodResult>& results, const VerdictThresholds& t = {});

//! A few lines for the terminal: per edit, the best result and why, then the methods by verdict.
std::string verdict_summary(const std::vector<MethodResult>& results, const std::vector<Assessment>& assessments);

//! CSS giving each verdict's page cells their background (classes named by to_string).
constexpr const char* kVerdictCss = ".good{background:#d8f0d0}.fair{background:#eef3c0}.poor{background:#fbe0b8}"
                                    ".broken{background:#f6c4c0}.failed{background:#e0e0e0}"
                                    ".not-judged{background:#dfe7f0}";

//! text with <, > and & escaped for HTML.
std::string html_escape(const std::string& text);

//! Inline SVG (no script) for one edit: horizontal bars per method of rigidity, detail distortion,
//! self-intersecting pairs and frame time (log axis), and a scatter of rigidity against frame time; bars
//! coloured by verdict, failed runs marked "failed".
std::string edit_charts_svg(const std::vector<MethodResult>& results, const std::vector<Assessment>& assessments,
                            const std::string& scene);

}  // namespace msd
