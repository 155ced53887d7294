// How a tensile job's summary reads (jobs/src/tensile_job_kind.cpp through summary_lines):
// fractions in %, a cyclic test's figures one line per cycle, the deposit only with NPs.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "mdem/job_kinds.h"

namespace mdem {
namespace {

std::vector<std::string> lines_of(const nlohmann::ordered_json& summary) {
  const SummaryLayout* layout = summary_layout("tensile");
  if (!layout) {
    ADD_FAILURE() << "no tensile layout";
    return {};
  }
  return summary_lines(*layout, summary);
}

bool has_line(const std::vector<std::string>& lines, const std::string& text) {
  for (const std::string& l : lines)
    if (l == text) return true;
  return false;
}

std::string joined(const std::vector<std::string>& lines) {
  std::string s;
  for (const std::string& l : lines) s += l + "\n";
  return s;
}

TEST(TensileReport, FractionsArePrintedInPercentTheJsonKeepsThem) {
  nlohmann::ordered_json s = {{"tubes_in_tension_at_2pct", 0.722222},
                              {"parents_in_tension_at_2pct", 0.758621},
                              {"mid_width_shrinkage_end", -0.00346548},
                              {"youngs_modulus_GPa", 5.16359},
                              {"final_strain", 0.03},
                              {"yield_strain", 0.0312},
                              {"porosity", 0.9012},
                              {"segments", 2100}};
  const auto lines = lines_of(s);
  EXPECT_TRUE(has_line(lines,
                       "tubes in tension at 2 % 72.2 %, parent tubes 75.9 %, width "
                       "shrinkage at the end -0.347 %"))
      << joined(lines);
  EXPECT_TRUE(has_line(lines, "Young's modulus 5.16359 GPa, yield strain 3.12 %, final strain 3 %"))
      << joined(lines);
  EXPECT_TRUE(has_line(lines, "segments 2100, porosity 90.12 %")) << joined(lines);
  // The JSON value is the fraction (the scale is for the printed text only).
  EXPECT_EQ(s["tubes_in_tension_at_2pct"].get<double>(), 0.722222);
}

TEST(TensileReport, AGivenStepReadsWithTheCriticalStepItWasCheckedAgainst) {
  // A caller's dt above safety × the automatic bound, accepted against the measured critical
  // step: both on one line, after the pre-relaxation's and before the relaxation's.
  nlohmann::ordered_json s = {{"prerelax_reason", "converged"},
                              {"step_origin", "given"},
                              {"step_dt_ps", 0.03},
                              {"step_critical_measured_ps", 0.049812},
                              {"step_over_measured", 0.602265},
                              {"step_bound_ps", 0.038504},
                              {"step_over_bound", 0.779140},
                              {"relax_ps", 4500.0}};
  const auto lines = lines_of(s);
  ASSERT_EQ(lines.size(), 3u) << joined(lines);
  EXPECT_EQ(lines[0], "pre-relaxation: converged");
  EXPECT_EQ(lines[1],
            "step of the relaxation and test: given, dt 0.03 ps, measured critical step 0.04981 "
            "ps, dt/measured 0.602, automatic bound 0.0385 ps, dt/bound 0.779");
  EXPECT_EQ(lines[2], "relaxation 4500 ps");
}

TEST(TensileReport, CyclicFiguresOneLinePerCycleInOrder) {
  nlohmann::ordered_json s = {{"cycles_complete", 2}};
  for (int k = 1; k <= 2; ++k) {
    const std::string c = "cycle_" + std::to_string(k) + "_";
    s[c + "loop_area_J_cm3"] = 0.0125 * k;
    s[c + "modulus_GPa"] = 2.5 + k;
    s[c + "phase_lead"] = 0.02 * k;
  }
  s["simulated_ps"] = 1500.0;
  const auto lines = lines_of(s);
  ASSERT_EQ(lines.size(), 4u) << joined(lines);
  EXPECT_EQ(lines[0], "cycles complete 2");
  EXPECT_EQ(lines[1],
            "cycle 1: loop area 0.0125 J/cm³, modulus 3.5 GPa, phase lead 2 % of the period");
  EXPECT_EQ(lines[2],
            "cycle 2: loop area 0.025 J/cm³, modulus 4.5 GPa, phase lead 4 % of the period");
  EXPECT_EQ(lines[3], "simulated 1500 ps");
  // The last cycle a test can have (1000) has its line too, before the run's own.
  nlohmann::ordered_json last = {{"cycle_1000_modulus_GPa", 3.0}, {"simulated_ps", 1.0}};
  const auto l2 = lines_of(last);
  ASSERT_EQ(l2.size(), 2u) << joined(l2);
  EXPECT_EQ(l2[0], "modulus 3 GPa");
}

}  // namespace
}  // namespace mdem
