#pragma once
// Pictures of a job's time series, drawn by gnuplot run as a child process on a generated script
// and data file in a temporary directory.
#include <stdexcept>
#include <string>
#include <vector>

#include "mdem/observe/snapshot.h"

namespace mdem::cli {

// gnuplot missing or failing, or no picture written (exit code kJobFailed).
struct PlotError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct PlotRequest {
  std::string title;                  // e.g. "j-20261124-153012-3f9a (twist)"
  std::vector<std::string> columns;   // every column of the job, in frame order
  std::vector<std::string> selected;  // the columns to draw (see select_columns)
  std::string x = "time_ps";          // horizontal axis: time_ps, step or a column
  double x_scale = 1.0;               // x values drawn as x_scale times the column's
  std::string x_label;                // the horizontal axis's label; "" = from x's name
  std::string out_path;               // .png or .svg
  // The default picture of a job (no --columns): the selected energies as changes from the first
  // frame, in panels by group (bond terms; van der Waals and contact; kinetic; work, dissipation
  // and balance), components that never change left out and named.
  bool energy_overview = false;
};

// The gnuplot terminal for a picture: "pngcairo" for .png, "svg" for .svg (any case); a
// UsageError naming the allowed extensions otherwise.
std::string plot_terminal(const std::string& out_path);

// The columns to draw: the comma-separated `wanted`, or when it is empty every column ending in
// "_eV" (the energy components). A UsageError names an unknown column and lists the available.
std::vector<std::string> select_columns(const std::vector<std::string>& available,
                                        const std::string& wanted);

// Checks the horizontal axis: time_ps, step or one of `available`; UsageError otherwise.
void check_x_column(const std::vector<std::string>& available, const std::string& x);

// An axis label with units from the column names' suffixes: {"kinetic_eV", "total_eV"} ->
// "energy (eV)"; "time_ps" -> "time (ps)"; a column without a known unit suffix -> its name.
std::string axis_label(const std::vector<std::string>& columns);

// Draws the selected columns against x with gnuplot, legends in words with units; columns of two
// units get a left and a right axis ($MDEM_GNUPLOT, else `gnuplot` on PATH).
// Throws PlotError (gnuplot missing: says to install gnuplot-nox).
void render_plot(const PlotRequest& request, const std::vector<SeriesFrame>& frames);

// Another picture by the same means: gnuplot runs `body` (with its data inline) after the common
// header (UTF-8, the terminal of out_path's extension, the output, line colours, a grid), with
// render_plot's checks. Throws PlotError, or UsageError for an unsupported extension.
void render_gnuplot(const std::string& out_path, const std::string& body);
// `s` as a gnuplot single-quoted string.
std::string gnuplot_quoted(const std::string& s);

}  // namespace mdem::cli
