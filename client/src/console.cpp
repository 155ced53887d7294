#include "console.h"

#include <unistd.h>

#include <csignal>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace mdem::cli {
namespace {

std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted = true; }

constexpr int kBarWidth = 30;

}  // namespace

void ProgressReporter::operator()(const JobProgress& p) {
  if (quiet_ || p.total_steps <= 0) return;
  const double frac = static_cast<double>(p.step) / p.total_steps;
  if (!frac0_) frac0_ = frac;
  const double wall = seconds();
  const double done = frac - *frac0_;
  const double eta = done > 0 ? wall * (1 - frac) / done : 0;
  if (tty_) {
    const int filled = static_cast<int>(frac * kBarWidth);
    err_ << "\r[" << std::string(filled, '#') << std::string(kBarWidth - filled, '-') << "] "
         << std::setw(3) << static_cast<int>(frac * 100) << "%  t " << std::fixed
         << std::setprecision(1) << p.time_ps << " ps  " << std::setw(9) << p.phase << "  ETA "
         << clock(eta) << "   " << std::defaultfloat << std::flush;
    bar_open_ = p.step != p.total_steps;
    if (!bar_open_) err_ << "\n";
  } else if (p.step == 0 || static_cast<int>(frac * 10) > last_decile_) {
    last_decile_ = static_cast<int>(frac * 10);
    err_ << "  step " << p.step << "/" << p.total_steps << "  t = " << std::fixed
         << std::setprecision(1) << p.time_ps << " ps  " << p.phase << "  wall " << clock(wall)
         << "  ETA " << clock(eta) << "\n"
         << std::defaultfloat;
  }
}

void ProgressReporter::note(const std::string& line) {
  if (bar_open_) err_ << "\r" << std::string(kBarWidth + 48, ' ') << "\r";
  err_ << line << "\n" << std::flush;
}

void ProgressReporter::finish() {
  if (bar_open_) err_ << "\n";
  bar_open_ = false;
}

std::string ProgressReporter::clock(double s) {
  const long t = static_cast<long>(s + 0.5);
  std::ostringstream o;
  o << t / 60 << ":" << std::setw(2) << std::setfill('0') << t % 60;
  return o.str();
}

double ProgressReporter::seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
}

bool is_terminal(const std::ostream& err) { return &err == &std::cerr && isatty(STDERR_FILENO); }

InterruptGuard::InterruptGuard() {
  g_interrupted = false;
  previous_ = std::signal(SIGINT, on_sigint);
}

InterruptGuard::~InterruptGuard() { std::signal(SIGINT, previous_); }

bool InterruptGuard::interrupted() { return g_interrupted.load(); }

namespace {

// The value at key of an object, or nullopt when absent or of another type.
template <class T>
std::optional<T> get(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key)) return std::nullopt;
  const json& v = j[key];
  if constexpr (std::is_same_v<T, std::string>) {
    if (v.is_string()) return v.get<std::string>();
  } else if constexpr (std::is_arithmetic_v<T>) {
    if (v.is_number()) return v.get<T>();
  }
  return std::nullopt;
}

// A JSON scalar as `mdem run` prints it: text bare, integers as integers, other numbers as
// the stream formats a double.
struct Scalar {
  const json& j;
};
std::ostream& operator<<(std::ostream& os, Scalar s) {
  if (s.j.is_string()) return os << s.j.get<std::string>();
  if (s.j.is_number_integer()) return os << s.j.get<long>();
  if (s.j.is_number()) return os << s.j.get<double>();
  return os << s.j.dump();
}
Scalar scalar(const json& j) { return Scalar{j}; }

bool has_all(const json& j, std::initializer_list<const char*> keys) {
  for (const char* k : keys)
    if (!j.is_object() || !j.contains(k)) return false;
  return true;
}

}  // namespace

void print_report(std::ostream& out, std::ostream& err, const json& doc,
                  std::optional<double> time_ps) {
  const std::string id = get<std::string>(doc, "job_id").value_or("?");
  const std::string kind = get<std::string>(doc, "kind").value_or("job");
  const std::string state = get<std::string>(doc, "state").value_or("?");
  const std::string reason = get<std::string>(doc, "reason").value_or("");
  const json summary = doc.is_object() && doc.contains("summary") ? doc["summary"] : json();
  const json acc = doc.is_object() && doc.contains("accuracy") ? doc["accuracy"] : json();
  const json perf = doc.is_object() && doc.contains("performance") ? doc["performance"] : json();
  if (!time_ps) time_ps = get<double>(summary, "simulated_ps");

  if (state == "FAILED") err << kind << " " << id << ": FAILED: " << reason << "\n";
  out << kind << " " << id << ": " << state;
  if (const auto steps = get<long>(perf, "steps")) {
    out << " after " << *steps << " steps";
    if (time_ps) out << " (" << *time_ps << " ps)";
  }
  out << "\n";
  if (state == "CANCELLED" && !reason.empty()) out << "  " << reason << "\n";
  if (state != "FAILED") {
    const json& s = summary;
    if (has_all(s, {"morphology", "twist_angle_deg", "shift_angle_deg", "topological_charge",
                    "max_topological_charge", "rope_radius_nm", "initial_rope_radius_nm",
                    "length_nm", "applied_torque_nNnm", "grip_reaction_nNnm"})) {
      out << "  morphology " << scalar(s["morphology"]) << ", twist angle "
          << scalar(s["twist_angle_deg"]) << " deg, end shift " << scalar(s["shift_angle_deg"])
          << " deg\n"
          << "  topological charge Q = " << scalar(s["topological_charge"]) << " (max "
          << scalar(s["max_topological_charge"]) << "), rope radius " << scalar(s["rope_radius_nm"])
          << " nm (initial " << scalar(s["initial_rope_radius_nm"]) << "), length "
          << scalar(s["length_nm"]) << " nm\n"
          << "  grip torque " << scalar(s["applied_torque_nNnm"]) << " nN·nm applied, "
          << scalar(s["grip_reaction_nNnm"]) << " nN·nm reaction\n";
    } else if (has_all(s, {"grains", "bonds", "porosity", "peak_force_nN",
                           "peak_force_displacement_nm", "loading_stiffness_nN_per_nm",
                           "final_force_nN", "final_displacement_nm", "bonds_yielded",
                           "bonds_broken", "fragments", "slip_max_nm", "slip_mean_nm"})) {
      out << "  " << scalar(s["grains"]) << " grains, " << scalar(s["bonds"]) << " bonds, porosity "
          << scalar(s["porosity"]) << "\n"
          << "  peak force " << scalar(s["peak_force_nN"])
          << " nN at h = " << scalar(s["peak_force_displacement_nm"]) << " nm, loading stiffness "
          << scalar(s["loading_stiffness_nN_per_nm"]) << " nN/nm; at the end "
          << scalar(s["final_force_nN"]) << " nN at h = " << scalar(s["final_displacement_nm"])
          << " nm\n"
          << "  bonds yielded " << scalar(s["bonds_yielded"]) << ", broken "
          << scalar(s["bonds_broken"]) << "; fragments " << scalar(s["fragments"])
          << "; grain slip max " << scalar(s["slip_max_nm"]) << " nm, mean "
          << scalar(s["slip_mean_nm"]) << " nm\n";
    } else if (s.is_object() && !s.empty()) {
      out << "  summary " << s.dump() << "\n";
    }
    const auto balance = get<double>(acc, "energy_balance_error");
    const auto dt = get<double>(acc, "dt_ps");
    const auto ratio = get<double>(acc, "dt_over_critical");
    if (balance && dt && ratio)
      out << "  energy balance error " << *balance << ", dt " << *dt * 1000 << " fs = " << *ratio
          << " x critical step\n";
  }
  const auto wall = get<double>(perf, "wall_s");
  const auto rate = get<double>(perf, "element_steps_per_s");
  if (wall && rate) out << "  " << *wall << " s wall, " << *rate << " element-steps/s\n";
  if (const auto db = get<std::string>(doc, "db"))
    out << "  results: mdem show " << id << " --db " << *db << "\n";
}

}  // namespace mdem::cli
