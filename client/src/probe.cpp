// `mdem probe`: one contact model evaluated for two elements given on the command line, printed
// as JSON. A quick way to see what the engine's vdW contact, parallel bond and nanoparticle
// contacts do at a given configuration (or, for the NP contacts, along a line: --scan, and beside
// a straight tube: --tube), and to check them against model.md by hand.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "flags.h"
#include "mdem/cli.h"
#include "mdem/core/cnt.h"
#include "mdem/core/elements.h"
#include "mdem/core/units.h"
#include "mdem/force/bond/parallel_bond.h"
#include "mdem/force/contact/anisotropic_vdw.h"
#include "mdem/force/contact/np_cnt_contact.h"
#include "mdem/force/contact/np_np_contact.h"
#include "mdem/scene/tube_builder.h"

namespace mdem::cli {
namespace {

constexpr double kMaxCoordinate = 1e6;   // nm; larger centre coordinates are refused
constexpr double kQuatTolerance = 1e-6;  // | |q| − 1 | allowed before a quaternion is refused
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = 180.0 / kPi;

constexpr const char* kModels = "vdw, vdw-pfc, bond, np-cnt, np-np";
const std::vector<std::string> kFlags = {"--model", "--x1", "--x2",   "--axis1", "--axis2",
                                         "--q1",    "--q2", "--tube", "--scan",  "--epsilon"};
constexpr long kMaxTubeSegments = 100001;
constexpr long kMaxScanPoints = 100000;

void print_probe_help(std::ostream& os) {
  os << "Usage: mdem probe --x2 X,Y,Z [flags]\n"
        "\n"
        "Evaluates one contact model for two elements (CNT segments or nanoparticles) and prints\n"
        "one JSON object: the energy (eV), the force (eV/nm and nN) and torque (eV and nN·nm) on\n"
        "each element, and the model's derived quantities.\n"
        "\n"
        "Flags:\n"
        "  --model M        vdw (default): anisotropic CNT-CNT van der Waals contact, exact\n"
        "                   gradient; vdw-pfc: the same energy, forces and aligning moment of\n"
        "                   the thesis' Table 2-3 (PFC compatibility); bond: intra-tube\n"
        "                   parallel bond; np-cnt: nanoparticle (element 2) against a CNT\n"
        "                   segment (element 1); np-np: two nanoparticles (model.md section 5)\n"
        "  --x1 X,Y,Z       centre of element 1 in nm (default 0,0,0)\n"
        "  --x2 X,Y,Z       centre of element 2 in nm (required)\n"
        "  --axis1 X,Y,Z    axis of element 1 (any non-zero vector; default 1,0,0); the\n"
        "                   orientation is the least rotation taking x onto it\n"
        "  --q1 W,X,Y,Z     orientation of element 1 as a unit quaternion (instead of --axis1)\n"
        "  --axis2, --q2    the same for element 2\n"
        "  --epsilon E      np-cnt, np-np: the well parameter eps0 in eV (defaults 0.05407 and\n"
        "                   0.009105; the thesis prints 0.005407 for np-cnt)\n"
        "  --tube N         np-cnt: element 1 is a straight tube of N segments centred at --x1\n"
        "                   along --axis1 (the energy and forces are summed over its segments;\n"
        "                   element 1's torque is about --x1)\n"
        "  --scan A:B:N     np-cnt, np-np: also print the energy and radial force at N points "
        "with\n"
        "                   element 2 moved from A to B nm from --x1 along the line through --x2,\n"
        "                   and the minimum along that line\n"
        "  -h, --help       show this help\n"
        "\n"
        "Coordinates are limited to |c| <= 1e6 nm; a quaternion must have unit norm within 1e-6\n"
        "(it is then normalised). Flags take their value as the next argument or after '='.\n"
        "\n"
        "For --model bond the rest state is two collinear (10,10) segments along x at distance\n"
        "T = 1.356 nm: element 1 at the origin, element 2 at (T,0,0), both with axis x. The\n"
        "flags give the deformed state.\n"
        "\n"
        "Examples:\n"
        "  mdem probe --x2 0,1.734357,0                  # parallel pair at the vdW minimum\n"
        "  mdem probe --x2 0,1.734357,0 --axis2 0,0,1    # crossed at 90 degrees\n"
        "  mdem probe --model bond --x2 1.366,0,0        # bond stretched by 0.01 nm\n"
        "  mdem probe --model np-cnt --x2 0,3.462,0 --tube 201 --scan 3.2:3.8:601\n"
        "                                                 # NP beside a long tube: rests at "
        "3.462\n";
}

Vec3 parse_position(const std::string& flag, const std::string& text) {
  const auto v = parse_list(flag, text, 3, "x,y,z in nm");
  for (const double c : v)
    if (std::abs(c) > kMaxCoordinate) {
      std::ostringstream msg;
      msg << flag << ": coordinate " << c
          << " nm is out of range (allowed |c| <= " << kMaxCoordinate << " nm)";
      throw UsageError(msg.str());
    }
  return Vec3(v[0], v[1], v[2]);
}

Quat parse_axis(const std::string& flag, const std::string& text) {
  const auto v = parse_list(flag, text, 3, "an axis x,y,z, any non-zero vector");
  Vec3 a(v[0], v[1], v[2]);
  const double scale = a.cwiseAbs().maxCoeff();  // rescale first so huge or tiny vectors work
  if (scale == 0)
    throw UsageError(flag + ": the axis must be a non-zero vector, got '" + text + "'");
  return quat_from_axis(a / scale);
}

Quat parse_quaternion(const std::string& flag, const std::string& text) {
  const auto v = parse_list(flag, text, 4, "a unit quaternion w,x,y,z");
  Quat q(v[0], v[1], v[2], v[3]);
  const double norm = q.norm();
  if (!(std::abs(norm - 1.0) <= kQuatTolerance)) {
    std::ostringstream msg;
    msg.precision(10);
    msg << flag << ": the quaternion w,x,y,z must have unit norm (within " << kQuatTolerance
        << "), got |q| = " << norm;
    throw UsageError(msg.str());
  }
  q.normalize();
  return q;
}

// --scan A:B:N: N points from A to B nm.
struct Scan {
  double from = 0, to = 0;
  long points = 0;
};

Scan parse_scan(const std::string& text) {
  const std::string allowed = "--scan: expected FROM:TO:N with 0 < FROM < TO (nm) and N in 2.." +
                              std::to_string(kMaxScanPoints) + " points, got '" + text + "'";
  const auto a = text.find(':'), b = a == std::string::npos ? a : text.find(':', a + 1);
  if (b == std::string::npos) throw UsageError(allowed);
  Scan s;
  try {
    s.from = parse_number("--scan", text.substr(0, a), "FROM in nm");
    s.to = parse_number("--scan", text.substr(a + 1, b - a - 1), "TO in nm");
    s.points = parse_integer("--scan", text.substr(b + 1), 2, kMaxScanPoints);
  } catch (const UsageError&) {
    throw UsageError(allowed);
  }
  if (!(s.from > 0 && s.to > s.from && s.to <= kMaxCoordinate)) throw UsageError(allowed);
  return s;
}

struct ProbeOptions {
  enum class Model { Vdw, VdwPfc, Bond, NpCnt, NpNp } model = Model::Vdw;
  std::string model_name = "vdw";
  Vec3 x1 = Vec3::Zero(), x2 = Vec3::Zero();
  Quat q1 = Quat::Identity(), q2 = Quat::Identity();
  std::optional<double> epsilon;  // np-cnt, np-np: ε0 (eV)
  long tube = 0;                  // np-cnt: element 1 is a tube of this many segments (0: one)
  std::optional<Scan> scan;       // np-cnt, np-np
  bool np() const { return model == Model::NpCnt || model == Model::NpNp; }
};

ProbeOptions parse_options(const std::vector<std::string>& args) {
  auto given = parse_flags(args, FlagSpec{kFlags, {}});

  ProbeOptions o;
  if (const auto it = given.find("--model"); it != given.end()) {
    o.model_name = it->second;
    if (o.model_name == "vdw")
      o.model = ProbeOptions::Model::Vdw;
    else if (o.model_name == "vdw-pfc")
      o.model = ProbeOptions::Model::VdwPfc;
    else if (o.model_name == "bond")
      o.model = ProbeOptions::Model::Bond;
    else if (o.model_name == "np-cnt")
      o.model = ProbeOptions::Model::NpCnt;
    else if (o.model_name == "np-np")
      o.model = ProbeOptions::Model::NpNp;
    else
      throw UsageError("--model: unknown model '" + o.model_name + "' (allowed: " + kModels + ")");
  }
  if (given.count("--x1")) o.x1 = parse_position("--x1", given["--x1"]);
  if (!given.count("--x2"))
    throw UsageError(
        "--x2 is required: the centre of element 2, x,y,z in nm (e.g. --x2 "
        "0,1.734357,0)");
  o.x2 = parse_position("--x2", given["--x2"]);
  for (const char* k : {"1", "2"}) {
    const std::string axis = std::string("--axis") + k, quat = std::string("--q") + k;
    Quat& q = (k[0] == '1') ? o.q1 : o.q2;
    if (given.count(axis) && given.count(quat))
      throw UsageError(axis + " and " + quat + " both given: give one orientation per element");
    if (given.count(axis)) q = parse_axis(axis, given[axis]);
    if (given.count(quat)) q = parse_quaternion(quat, given[quat]);
  }
  for (const char* f : {"--epsilon", "--scan"})
    if (given.count(f) && !o.np())
      throw UsageError(std::string(f) + " applies to --model np-cnt or np-np, not '" +
                       o.model_name + "'");
  if (given.count("--tube") && o.model != ProbeOptions::Model::NpCnt)
    throw UsageError("--tube applies to --model np-cnt, not '" + o.model_name + "'");
  if (given.count("--epsilon"))
    o.epsilon = parse_in_range("--epsilon", given["--epsilon"], 1e-9, 10.0, "eV");
  if (given.count("--tube")) o.tube = parse_integer("--tube", given["--tube"], 1, kMaxTubeSegments);
  if (given.count("--scan")) o.scan = parse_scan(given["--scan"]);
  return o;
}

// −0 printed as 0: a zero torque reads better as 0.0 than as -0.0.
double clean(double c) { return c == 0 ? 0.0 : c; }

json vec_json(const Vec3& v) { return json::array({clean(v.x()), clean(v.y()), clean(v.z())}); }

json element_json(const Vec3& x, const Quat& q, const Vec3& f, const Vec3& t) {
  json e;
  e["x_nm"] = vec_json(x);
  e["axis"] = vec_json(q * Vec3::UnitX());
  e["q_wxyz"] = json::array({q.w(), q.x(), q.y(), q.z()});
  e["force_eV_per_nm"] = vec_json(f);
  e["force_nN"] = vec_json(f.unaryExpr([](double c) { return units::to_nN(c); }));
  e["torque_eV"] = vec_json(t);
  e["torque_nN_nm"] = vec_json(t.unaryExpr([](double c) { return units::to_nNnm(c); }));
  return e;
}

bool finite(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, double e) {
  return a.allFinite() && b.allFinite() && c.allFinite() && d.allFinite() && std::isfinite(e);
}

// The vdW contact (model.md §4) plus its geometry: R, D, δ(θ), γ, θ.
json probe_vdw(const ProbeOptions& o) {
  VdwParams p;
  if (o.model == ProbeOptions::Model::VdwPfc) p.torque = VdwTorque::Pfc;
  const Vec3 d = o.x2 - o.x1;
  const double R = d.norm();
  if (R == 0)
    throw UsageError(
        "--x2: the centres coincide with --x1; the vdW contact needs distinct "
        "centres");
  const Vec3 b1 = o.q1 * Vec3::UnitX();
  Vec3 b2 = o.q2 * Vec3::UnitX();
  const VdwPairResult r = vdw_pair(p, o.x1, b1, o.x2, b2);
  if (!finite(r.f1, r.f2, r.t1, r.t2, r.energy))
    throw std::runtime_error("the vdW model returned a non-finite result at this configuration");

  // Geometry as model.md §4 defines it; θ folded into [0°, 90°] (δ is symmetric about 90°).
  if (b1.dot(b2) < 0) b2 = -b2;
  const double gamma = std::acos(std::clamp(b1.dot(b2), -1.0, 1.0));
  const Vec3 b3 = (b1 + b2).normalized();
  const double theta = std::acos(std::clamp(std::abs(b3.dot(d / R)), 0.0, 1.0));
  const double delta = vdw_delta(p, theta);

  json out;
  out["energy_eV"] = r.energy;
  out["element1"] = element_json(o.x1, o.q1, r.f1, r.t1);
  out["element2"] = element_json(o.x2, o.q2, r.f2, r.t2);
  json g;
  g["R_nm"] = R;
  g["D"] = R / (p.radius * delta) - 2.0;
  g["delta"] = delta;
  g["gamma_deg"] = gamma * kDeg;
  g["theta_deg"] = theta * kDeg;
  g["cutoff_nm"] = p.cutoff();
  g["within_cutoff"] = R < p.cutoff();
  g["torque"] = p.torque == VdwTorque::Pfc ? "pfc" : "exact";
  out["vdw"] = g;
  return out;
}

// The intra-tube parallel bond (model.md §3), rest state two collinear segments along x at T.
json probe_bond(const ProbeOptions& o) {
  constexpr double T = cnt::kSegmentLength;
  Elements el;
  el.add(cnt_segment(Vec3::Zero(), Quat::Identity(), 0, 0));
  el.add(cnt_segment(Vec3(T, 0, 0), Quat::Identity(), 0, 1));
  const Bond b = make_bond(el, 0, 1, cnt_bond_stiffness());
  const BondResult r = bond_eval(b, o.x1, o.q1, o.x2, o.q2);
  const BondDeformation d = bond_deformation(b, o.x1, o.q1, o.x2, o.q2);
  if (!finite(r.fi, r.fj, r.ti, r.tj, r.energy()) || !d.u_s.allFinite() || !d.theta_b.allFinite() ||
      !std::isfinite(d.u_n) || !std::isfinite(d.theta_t))
    throw std::runtime_error("the bond model returned a non-finite result at this configuration");

  json out;
  out["energy_eV"] = r.energy();
  out["element1"] = element_json(o.x1, o.q1, r.fi, r.ti);
  out["element2"] = element_json(o.x2, o.q2, r.fj, r.tj);
  json g;
  g["rest_length_nm"] = T;
  g["axis"] = vec_json(d.n);
  g["u_n_nm"] = d.u_n;
  g["u_s_nm"] = d.u_s.norm();
  g["twist_deg"] = d.theta_t * kDeg;
  g["bending_deg"] = d.theta_b.norm() * kDeg;
  g["energy_terms_eV"] = {{"tension", r.e_tension},
                          {"shear", r.e_shear},
                          {"bending", r.e_bending},
                          {"torsion", r.e_torsion}};
  out["bond"] = g;
  return out;
}

// An NP contact evaluated for element 2 at a given position: energy, forces and torques.
using NpLaw = std::function<PairForces(const Vec3& x2)>;

// The curve of --scan: element 2 at x1 + R·n for N values of R, n the unit line from x1 to x2,
// with the radial force n·F2; the minimum is the lowest sample refined by golden section between
// its neighbours.
json scan_json(const ProbeOptions& o, const NpLaw& law) {
  const Scan& s = *o.scan;
  const Vec3 n = (o.x2 - o.x1).normalized();
  auto energy = [&](double R) { return law(o.x1 + R * n).energy; };
  json curve = json::array();
  std::vector<double> Rs, Us;
  for (long k = 0; k < s.points; ++k) {
    const double R = s.from + (s.to - s.from) * static_cast<double>(k) / (s.points - 1);
    const PairForces r = law(o.x1 + R * n);
    if (!std::isfinite(r.energy) || !r.f2.allFinite())
      throw std::runtime_error(
          "the model returned a non-finite result at R = " + std::to_string(R) + " nm of the scan");
    curve.push_back(
        {{"R_nm", R}, {"energy_eV", r.energy}, {"radial_force_eV_per_nm", n.dot(r.f2)}});
    Rs.push_back(R);
    Us.push_back(r.energy);
  }
  const auto k = static_cast<std::size_t>(std::min_element(Us.begin(), Us.end()) - Us.begin());
  double a = Rs[k == 0 ? 0 : k - 1], b = Rs[std::min(k + 1, Rs.size() - 1)];
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int it = 0; it < 200 && b - a > 1e-12 * b; ++it) {
    const double c = b - g * (b - a), d = a + g * (b - a);
    if (energy(c) < energy(d))
      b = d;
    else
      a = c;
  }
  const double R = 0.5 * (a + b);
  json m;
  m["R_nm"] = R;
  m["energy_eV"] = energy(R);
  m["at_scan_end"] = (k == 0 || k + 1 == Rs.size());
  json out;
  out["curve"] = curve;
  out["minimum"] = m;
  return out;
}

// The NP law at --x2: energy, both elements' forces and torques, the model's geometry under
// `key`, and the --scan curve when asked for. Refused when the centres coincide or the result is
// not finite.
json np_result_json(const ProbeOptions& o, const NpLaw& law, const char* what, const char* key,
                    const json& geometry) {
  if ((o.x2 - o.x1).norm() == 0)
    throw UsageError("--x2: the centres coincide with --x1; the NP contact needs distinct centres");
  const PairForces r = law(o.x2);
  if (!finite(r.f1, r.f2, r.t1, r.t2, r.energy))
    throw std::runtime_error(std::string("the ") + what +
                             " model returned a non-finite result at this configuration");
  json out;
  out["energy_eV"] = r.energy;
  out["element1"] = element_json(o.x1, o.q1, r.f1, r.t1);
  out["element2"] = element_json(o.x2, o.q2, r.f2, r.t2);
  out[key] = geometry;
  if (o.scan) out.update(scan_json(o, law));
  return out;
}

// An NP (element 2) against a CNT segment or a straight tube (element 1) (model.md §5).
json probe_np_cnt(const ProbeOptions& o) {
  NpCntParams p;
  if (o.epsilon) p.epsilon = *o.epsilon;
  const NpCntKernel k(p);
  const Vec3 b = o.q1 * Vec3::UnitX();
  const long n = std::max(o.tube, 1L);
  // Element 1's centres: one segment at x1, or n segments spaced T along b centred at x1.
  std::vector<Vec3> centres;
  for (long s = 0; s < n; ++s)
    centres.push_back(o.x1 + (static_cast<double>(s) - 0.5 * static_cast<double>(n - 1)) *
                                 cnt::kSegmentLength * b);
  const NpLaw law = [&](const Vec3& x2) {
    PairForces sum;  // 1 = the segment(s), 2 = the NP
    for (const Vec3& c : centres) {
      const PairForces r = k.evaluate(x2, c, b);
      sum.energy += r.energy;
      sum.f2 += r.f1;
      sum.f1 += r.f2;
      sum.t1 += r.t2 + (c - o.x1).cross(r.f2);
    }
    return sum;
  };
  const Vec3 d = o.x2 - o.x1;
  const double R = d.norm();
  const double c = std::abs(b.dot(d / R));
  const double theta = std::acos(std::min(c, 1.0));
  VdwParams shape;
  shape.C = p.C;
  const double delta = vdw_delta(shape, theta);
  json g;
  g["R_nm"] = R;
  g["theta_deg"] = theta * kDeg;
  g["delta"] = delta;
  g["D"] = R / (p.rho * delta) - 2.0;
  g["rho_nm"] = p.rho;
  g["epsilon_eV"] = p.epsilon;
  g["cutoff_nm"] = p.cutoff();
  g["within_cutoff"] = R < p.cutoff();
  if (o.tube > 0) g["tube_segments"] = o.tube;
  return np_result_json(o, law, "NP-CNT", "np_cnt", g);
}

// Two nanoparticles (model.md §5).
json probe_np_np(const ProbeOptions& o) {
  NpNpParams p;
  if (o.epsilon) p.epsilon = *o.epsilon;
  const NpNpKernel k(p);
  const NpLaw law = [&](const Vec3& x2) {
    PairForces r;
    k.evaluate(x2 - o.x1, r);
    return r;
  };
  const double R = (o.x2 - o.x1).norm();
  json g;
  g["R_nm"] = R;
  g["gap_nm"] = R - 2.0 * p.radius;
  g["D"] = R / p.radius - 2.0;
  g["epsilon_eV"] = p.epsilon;
  g["cutoff_nm"] = p.cutoff();
  g["within_cutoff"] = R < p.cutoff();
  return np_result_json(o, law, "NP-NP", "np_np", g);
}

json probe_model(const ProbeOptions& o) {
  switch (o.model) {
    case ProbeOptions::Model::Bond:
      return probe_bond(o);
    case ProbeOptions::Model::NpCnt:
      return probe_np_cnt(o);
    case ProbeOptions::Model::NpNp:
      return probe_np_np(o);
    default:
      return probe_vdw(o);
  }
}

}  // namespace

int probe(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  if (wants_help(args)) {
    print_probe_help(out);
    return kOk;
  }
  try {
    const ProbeOptions o = parse_options(args);
    json result = probe_model(o);
    json doc;
    doc["model"] = o.model_name;
    doc.update(result);
    write_json(out, doc);
    out << "\n";
    return kOk;
  } catch (const UsageError& e) {
    err << "mdem probe: " << e.what() << "\nRun 'mdem probe --help' for the flags.\n";
    return kUsage;
  } catch (const std::exception& e) {
    err << "mdem probe: error: " << e.what() << "\n";
    return kJobFailed;
  }
}

}  // namespace mdem::cli
