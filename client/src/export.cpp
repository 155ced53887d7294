// Writers of extended XYZ, VTK XML PolyData + .pvd, and CSV; see export.h.
#include "export.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include "flags.h"

namespace mdem::cli {
namespace {

namespace fs = std::filesystem;

// %.17g: enough digits for every double to read back exactly.
void num(std::string& out, double v) {
  char buf[32];
  const int n = std::snprintf(buf, sizeof buf, "%.17g", v);
  out.append(buf, static_cast<std::size_t>(n));
}

std::string num(double v) {
  std::string s;
  num(s, v);
  return s;
}

// A name usable as an extended-XYZ property (letters, digits, underscore).
std::string property_name(const std::string& name) {
  std::string out = name;
  for (char& c : out)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
  return out.empty() ? "_" : out;
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string csv_cell(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

Vec3 body_x_axis(const Quat& q) { return q * Vec3::UnitX(); }

// Opens a file for writing, creating its parent directories.
std::ofstream open_out(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  std::error_code ec;
  if (!parent.empty()) fs::create_directories(parent, ec);
  if (ec) throw ExportError("cannot create the directory of '" + path + "': " + ec.message());
  std::ofstream os(path, std::ios::binary | std::ios::trunc);
  if (!os) throw ExportError("cannot write '" + path + "': " + std::strerror(errno));
  return os;
}

void close_out(std::ofstream& os, const std::string& path) {
  os.close();
  if (!os) throw ExportError("cannot write '" + path + "' (disk full or not writable?)");
}

std::size_t require_snapshots(const ResultsStore& store, const JobRecord& job, const char* fmt) {
  const std::size_t n = store.snapshot_count(job.id);
  if (n == 0)
    throw ExportError("job '" + job.id + "' has no snapshots: nothing to export as " + fmt +
                      " (the series can be exported with --format csv)");
  return n;
}

Snapshot load_snapshot(const ResultsStore& store, const JobRecord& job, std::size_t k) {
  auto s = store.snapshot(job.id, k);
  if (!s) throw ExportError("job '" + job.id + "': snapshot " + std::to_string(k) + " vanished");
  return std::move(*s);
}

// ---- extended XYZ -----------------------------------------------------------------------------

std::string xyz_header(const Snapshot& s) {
  std::string h =
      "Properties=species:S:1:pos:R:3:orientation:R:4:axis:R:3:radius:R:1:tube:I:1:index:I:1";
  for (const auto& [name, values] : s.scalars) {
    h += ':';
    h += property_name(name);
    h += ":R:1";
  }
  return h + " Time=" + num(s.time_ps) + " Step=" + std::to_string(s.step);
}

std::string xyz_line(const Snapshot& s, std::size_t i) {
  std::string line = species_of(s.kind[i]);
  const Quat& q = s.q[i];
  const Vec3 a = body_x_axis(q);
  // OVITO's Orientation property is the quaternion in X Y Z W order (W the scalar part).
  for (double v : {s.x[i].x(), s.x[i].y(), s.x[i].z(), q.x(), q.y(), q.z(), q.w(), a.x(), a.y(),
                   a.z(), s.radius[i]}) {
    line += ' ';
    num(line, v);
  }
  line += ' ' + std::to_string(s.tube[i]) + ' ' + std::to_string(s.index[i]);
  for (const auto& [name, values] : s.scalars) {
    line += ' ';
    num(line, values[i]);
  }
  return line;
}

// ---- VTK XML ----------------------------------------------------------------------------------

// Writes <DataArray> with `comps` components per tuple; `tuple(line, i)` appends tuple i.
template <class F>
void data_array(std::ostream& os, const char* type, const std::string& name, int comps,
                std::size_t n, F tuple) {
  os << "        <DataArray type=\"" << type << "\"";
  if (!name.empty()) os << " Name=\"" << xml_escape(name) << "\"";
  os << " NumberOfComponents=\"" << comps << "\" format=\"ascii\">\n";
  std::string line;
  for (std::size_t i = 0; i < n; ++i) {
    line = "          ";
    tuple(line, i);
    os << line << '\n';
  }
  os << "        </DataArray>\n";
}

void append_numbers(std::string& line, std::initializer_list<double> values) {
  bool first = true;
  for (double v : values) {
    if (!first) line += ' ';
    num(line, v);
    first = false;
  }
}

void vtp_point_data(std::ostream& os, const Snapshot& s) {
  const std::size_t n = s.size();
  os << "      <PointData Scalars=\"radius\" Vectors=\"axis\">\n";
  data_array(os, "Float64", "orientation", 4, n, [&](std::string& l, std::size_t i) {
    append_numbers(l, {s.q[i].x(), s.q[i].y(), s.q[i].z(), s.q[i].w()});
  });
  data_array(os, "Float64", "axis", 3, n, [&](std::string& l, std::size_t i) {
    const Vec3 a = body_x_axis(s.q[i]);
    append_numbers(l, {a.x(), a.y(), a.z()});
  });
  data_array(os, "Float64", "radius", 1, n,
             [&](std::string& l, std::size_t i) { num(l, s.radius[i]); });
  data_array(os, "Int32", "kind", 1, n,
             [&](std::string& l, std::size_t i) { l += std::to_string(s.kind[i]); });
  data_array(os, "Int32", "tube", 1, n,
             [&](std::string& l, std::size_t i) { l += std::to_string(s.tube[i]); });
  data_array(os, "Int32", "index", 1, n,
             [&](std::string& l, std::size_t i) { l += std::to_string(s.index[i]); });
  for (const auto& [name, values] : s.scalars)
    data_array(os, "Float64", name, 1, n,
               [&](std::string& l, std::size_t i) { num(l, values[i]); });
  os << "      </PointData>\n";
}

void vtp_points(std::ostream& os, const Snapshot& s) {
  os << "      <Points>\n";
  data_array(os, "Float64", "position", 3, s.size(), [&](std::string& l, std::size_t i) {
    append_numbers(l, {s.x[i].x(), s.x[i].y(), s.x[i].z()});
  });
  os << "      </Points>\n";
}

// Point ids of each tube with at least two segments, in index order; tubes by ascending id.
std::vector<std::vector<std::size_t>> tube_polylines(const Snapshot& s) {
  std::map<std::int32_t, std::vector<std::pair<std::int32_t, std::size_t>>> tubes;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s.tube[i] >= 0) tubes[s.tube[i]].emplace_back(s.index[i], i);
  std::vector<std::vector<std::size_t>> lines;
  for (auto& [tube, members] : tubes) {
    if (members.size() < 2) continue;
    std::sort(members.begin(), members.end());
    std::vector<std::size_t> ids;
    for (const auto& m : members) ids.push_back(m.second);
    lines.push_back(std::move(ids));
  }
  return lines;
}

// <Verts> or <Lines>: connectivity and offsets of the given cells.
void vtp_cells(std::ostream& os, const char* tag,
               const std::vector<std::vector<std::size_t>>& cells) {
  std::vector<std::size_t> connectivity, offsets;
  for (const auto& c : cells) {
    connectivity.insert(connectivity.end(), c.begin(), c.end());
    offsets.push_back(connectivity.size());
  }
  os << "      <" << tag << ">\n";
  data_array(os, "Int64", "connectivity", 1, connectivity.size(),
             [&](std::string& l, std::size_t i) { l += std::to_string(connectivity[i]); });
  data_array(os, "Int64", "offsets", 1, offsets.size(),
             [&](std::string& l, std::size_t i) { l += std::to_string(offsets[i]); });
  os << "      </" << tag << ">\n";
}

std::vector<std::vector<std::size_t>> one_vertex_per_point(std::size_t n) {
  std::vector<std::vector<std::size_t>> verts(n);
  for (std::size_t i = 0; i < n; ++i) verts[i] = {i};
  return verts;
}

// ---- CSV --------------------------------------------------------------------------------------

std::string csv_row(const SeriesFrame& f) {
  std::string row = std::to_string(f.step) + ',' + num(f.time_ps);
  for (double v : f.values) {
    row += ',';
    num(row, v);
  }
  return row;
}

}  // namespace

const char* species_of(std::int32_t kind) {
  switch (kind) {
    case 0:
      return "C";
    case 1:
      return "Si";
    case 2:
      return "G";
    default:
      return "X";
  }
}

void write_xyz_frame(std::ostream& os, const Snapshot& s) {
  os << s.size() << '\n' << xyz_header(s) << '\n';
  for (std::size_t i = 0; i < s.size(); ++i) os << xyz_line(s, i) << '\n';
}

void write_vtp(std::ostream& os, const Snapshot& s) {
  const auto lines = tube_polylines(s);
  os << "<?xml version=\"1.0\"?>\n"
        "<!-- mdem snapshot, step "
     << s.step << ", time " << num(s.time_ps)
     << " ps; lengths in nm.\n"
        "     Points: element centres. orientation: the unit quaternion body -> world in x y z w\n"
        "     order (w the scalar part, as OVITO's Orientation). axis: body x in the world frame\n"
        "     (a CNT segment's axis). Verts: one per element. Lines: one polyline per tube\n"
        "     through its segments in index order. -->\n"
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
        "header_type=\"UInt64\">\n"
        "  <PolyData>\n"
        "    <FieldData>\n"
        "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
        "format=\"ascii\">"
     << num(s.time_ps)
     << "</DataArray>\n"
        "      <DataArray type=\"Int64\" Name=\"Step\" NumberOfTuples=\"1\" format=\"ascii\">"
     << s.step
     << "</DataArray>\n"
        "    </FieldData>\n"
     << "    <Piece NumberOfPoints=\"" << s.size() << "\" NumberOfVerts=\"" << s.size()
     << "\" NumberOfLines=\"" << lines.size() << "\" NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n";
  vtp_point_data(os, s);
  vtp_points(os, s);
  vtp_cells(os, "Verts", one_vertex_per_point(s.size()));
  vtp_cells(os, "Lines", lines);
  os << "    </Piece>\n  </PolyData>\n</VTKFile>\n";
}

void write_pvd(std::ostream& os, const std::vector<std::pair<double, std::string>>& datasets) {
  os << "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
        "  <Collection>\n";
  for (const auto& [time, file] : datasets)
    os << "    <DataSet timestep=\"" << num(time) << "\" group=\"\" part=\"0\" file=\""
       << xml_escape(file) << "\"/>\n";
  os << "  </Collection>\n</VTKFile>\n";
}

void write_csv(std::ostream& os, const std::vector<std::string>& columns,
               const std::vector<SeriesFrame>& frames) {
  os << "step,time_ps";
  for (const std::string& c : columns) os << ',' << csv_cell(c);
  os << '\n';
  for (const SeriesFrame& f : frames) os << csv_row(f) << '\n';
}

std::vector<std::string> export_xyz(const ResultsStore& store, const JobRecord& job,
                                    const std::string& path) {
  const std::size_t count = require_snapshots(store, job, "xyz");
  std::ofstream os = open_out(path);
  for (std::size_t k = 0; k < count; ++k) write_xyz_frame(os, load_snapshot(store, job, k));
  close_out(os, path);
  return {path};
}

std::vector<std::string> export_vtk(const ResultsStore& store, const JobRecord& job,
                                    const std::string& pvd_path) {
  const fs::path pvd(pvd_path);
  if (pvd.extension() != ".pvd")
    throw UsageError("--out: '" + pvd_path + "' must end in .pvd for --format vtk");
  const std::size_t count = require_snapshots(store, job, "vtk");
  std::vector<std::pair<double, std::string>> datasets;
  std::vector<std::string> written;
  for (std::size_t k = 0; k < count; ++k) {
    const Snapshot s = load_snapshot(store, job, k);
    const std::string name = pvd.stem().string() + "_" + std::to_string(k) + ".vtp";
    const std::string path = (pvd.parent_path() / name).string();
    std::ofstream os = open_out(path);
    write_vtp(os, s);
    close_out(os, path);
    datasets.emplace_back(s.time_ps, name);
    written.push_back(path);
  }
  std::ofstream os = open_out(pvd_path);
  write_pvd(os, datasets);
  close_out(os, pvd_path);
  written.insert(written.begin(), pvd_path);
  return written;
}

std::vector<std::string> export_csv(const ResultsStore& store, const JobRecord& job,
                                    const std::string& path) {
  const std::vector<std::string> columns = store.columns(job.id);
  const std::vector<SeriesFrame> frames = store.frames(job.id);
  std::ofstream os = open_out(path);
  write_csv(os, columns, frames);
  close_out(os, path);
  return {path};
}

}  // namespace mdem::cli
