#include "thermo.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

namespace mdem::cli {
namespace {

// Unit suffixes of frame column names, longest first, as printed.
const std::vector<std::pair<std::string, std::string>> kUnits = {
    {"_nN_per_nm", "nN/nm"}, {"_nNnm", "nN·nm"}, {"_deg", "deg"}, {"_eV", "eV"},
    {"_nm", "nm"},           {"_nN", "nN"},      {"_ps", "ps"}};

// The key observables of the kinds this build runs, in the order printed.
const std::map<std::string, std::vector<std::string>>& key_observables() {
  static const std::map<std::string, std::vector<std::string>> k = {
      {"twist", {"applied_torque_nNnm", "twist_angle_deg", "rope_radius_nm", "topological_charge"}},
      {"compression", {"displacement_nm", "force_nN", "bonds_broken", "fragments"}}};
  return k;
}

// Energy columns that are not a stored term (job.h's energy_columns).
bool ledger_column(const std::string& c) {
  for (const char* n : {"kinetic_translational_eV", "kinetic_rotational_eV", "external_work_eV",
                        "dissipated_eV", "total_eV", "balance_residual_eV"})
    if (c == n) return true;
  return false;
}

bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

}  // namespace

std::string ThermoColumn::header() const { return unit.empty() ? name : name + "[" + unit + "]"; }

std::pair<std::string, std::string> split_unit(const std::string& column) {
  for (const auto& [suffix, unit] : kUnits)
    if (ends_with(column, suffix) && column.size() > suffix.size())
      return {column.substr(0, column.size() - suffix.size()), unit};
  return {column, ""};
}

std::vector<ThermoColumn> thermo_columns(const std::string& kind,
                                         const std::vector<std::string>& frame_columns) {
  auto index = [&](const std::string& name) {
    const auto it = std::find(frame_columns.begin(), frame_columns.end(), name);
    return it == frame_columns.end() ? -1 : static_cast<int>(it - frame_columns.begin());
  };
  std::vector<ThermoColumn> c;
  c.push_back({"Step", "", {}, ThermoColumn::Kind::Step});
  c.push_back({"Time", "ps", {}, ThermoColumn::Kind::Time});
  // The stored terms the job has, in its order.
  for (std::size_t i = 0; i < frame_columns.size(); ++i)
    if (ends_with(frame_columns[i], "_eV") && !ledger_column(frame_columns[i])) {
      auto [name, unit] = split_unit(frame_columns[i]);
      c.push_back({name, unit, {static_cast<int>(i)}});
    }
  const int kt = index("kinetic_translational_eV"), kr = index("kinetic_rotational_eV");
  if (kt >= 0 && kr >= 0) c.push_back({"kinetic", "eV", {kt, kr}});
  c.push_back({"balance_error", "", {}, ThermoColumn::Kind::BalanceError});
  std::vector<std::string> keys;
  if (const auto it = key_observables().find(kind); it != key_observables().end()) {
    keys = it->second;
  } else {
    for (const std::string& col : frame_columns)
      if (!ends_with(col, "_eV") && col != "time_ps") keys.push_back(col);
  }
  for (const std::string& k : keys)
    if (const int i = index(k); i >= 0) {
      auto [name, unit] = split_unit(k);
      c.push_back({name, unit, {i}});
    }
  return c;
}

ThermoTable::ThermoTable(std::vector<ThermoColumn> columns, double every_ps, double frame_ps)
    : columns_(std::move(columns)), every_ps_(every_ps), frame_ps_(frame_ps) {
  // Wide enough for the header and for "-1.23457e-05" (%.6g at its widest).
  for (const ThermoColumn& c : columns_)
    widths_.push_back(std::max<int>(12, static_cast<int>(c.header().size())));
}

std::string ThermoTable::header() const {
  std::ostringstream o;
  for (std::size_t k = 0; k < columns_.size(); ++k) {
    const std::string h = columns_[k].header();
    // "·" is two bytes and one column.
    const int extra = static_cast<int>(std::count(h.begin(), h.end(), '\xc2'));
    o << (k ? " " : "") << std::string(std::max(0, widths_[k] + extra - (int)h.size()), ' ') << h;
  }
  return o.str();
}

bool ThermoTable::due(const SeriesFrame& f) const {
  const long bin = static_cast<long>(std::floor((f.time_ps + 0.5 * frame_ps_) / every_ps_));
  return last_step_ < 0 || bin > last_bin_;
}

std::string ThermoTable::row(const SeriesFrame& f, double balance_error) {
  last_bin_ =
      std::max(last_bin_, static_cast<long>(std::floor((f.time_ps + 0.5 * frame_ps_) / every_ps_)));
  last_step_ = f.step;
  std::ostringstream o;
  for (std::size_t k = 0; k < columns_.size(); ++k) {
    const ThermoColumn& c = columns_[k];
    std::string cell;
    switch (c.kind) {
      case ThermoColumn::Kind::Step:
        cell = std::to_string(f.step);
        break;
      case ThermoColumn::Kind::Time:
        cell = number(f.time_ps);
        break;
      case ThermoColumn::Kind::BalanceError:
        cell = number(balance_error);
        break;
      case ThermoColumn::Kind::Frame: {
        double v = 0;
        for (int i : c.sources) v += i < static_cast<int>(f.values.size()) ? f.values[i] : NAN;
        cell = number(v);
        break;
      }
    }
    o << (k ? " " : "") << std::string(std::max(0, widths_[k] - (int)cell.size()), ' ') << cell;
  }
  return o.str();
}

double default_thermo_every(double duration_ps, double frame_ps) {
  if (!(frame_ps > 0)) return duration_ps > 0 ? duration_ps / 15 : 1.0;
  const double frames = std::ceil(duration_ps / 15 / frame_ps - 1e-9);
  return std::max(1.0, frames) * frame_ps;
}

}  // namespace mdem::cli
