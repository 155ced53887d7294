#pragma once
// The work-precision picture of a study (`mdem plot ID` for a study id): each result's relative
// error against the run's wall time on log-log axes, one curve per result, each point labelled
// with its varied values, the runs' energy-balance errors as a dashed curve beside them, and the
// reference named in the title.
#include <string>

#include "study_table.h"

namespace mdem::cli {

// What `mdem plot` wrote: the curves drawn and the results left out (no error above zero).
struct StudyPlotInfo {
  int curves = 0;
  std::vector<std::string> left_out;
};

// Throws PlotError when there is nothing to draw (no run succeeded, every error zero).
StudyPlotInfo render_study_plot(const StudyTable& t, const std::string& out_path);

}  // namespace mdem::cli
