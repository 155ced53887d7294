// Writers of extended XYZ, VTK XML PolyData + .pvd, and CSV; see export.h.
#include "export.h"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>

#include "flags.h"
#include "mdem/spec.h"

namespace mdem::cli {
namespace {

namespace fs = std::filesystem;

constexpr std::int32_t kWallKind = static_cast<std::int32_t>(ElementKind::Wall);

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

// Walls (platens) are surfaces, not particles: left out of the particle files.
bool is_wall(const Snapshot& s, std::size_t i) { return s.kind[i] == kWallKind; }

std::vector<std::size_t> particle_ids(const Snapshot& s) {
  std::vector<std::size_t> ids;
  ids.reserve(s.size());
  for (std::size_t i = 0; i < s.size(); ++i)
    if (!is_wall(s, i)) ids.push_back(i);
  return ids;
}

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

std::string xyz_line(const Snapshot& s, std::size_t i, const char* grain) {
  std::string line = species_of(s.kind[i], grain);
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

// ---- VTK XML, binary ---------------------------------------------------------------------------

// The appended data of a VTK XML file (format="appended", encoding raw): each array as
// vtkZLibDataCompressor writes it with header_type UInt64: the block count, the uncompressed block
// size, the size of the last block when partial (0 when full), each block's compressed size, then
// the zlib streams of the blocks.
class AppendedData {
 public:
  // Appends an array of `bytes` bytes; returns its offset (from the '_' that starts the data).
  std::size_t add(const void* data, std::size_t bytes) {
    const std::size_t offset = out_.size();
    const auto* p = static_cast<const unsigned char*>(data);
    const std::size_t blocks = (bytes + kBlock - 1) / kBlock;
    std::vector<std::uint64_t> header = {blocks, kBlock, bytes % kBlock};
    std::string streams;
    for (std::size_t b = 0; b < blocks; ++b) {
      const std::size_t n = std::min(kBlock, bytes - b * kBlock);
      uLongf size = compressBound(static_cast<uLong>(n));
      std::string z(size, '\0');
      if (compress2(reinterpret_cast<Bytef*>(z.data()), &size, p + b * kBlock,
                    static_cast<uLong>(n), Z_DEFAULT_COMPRESSION) != Z_OK)
        throw ExportError("zlib could not compress a VTK data array");
      header.push_back(size);
      streams.append(z.data(), size);
    }
    for (std::uint64_t h : header) put(h);
    out_ += streams;
    return offset;
  }
  template <class T>
  std::size_t add(const std::vector<T>& v) {
    return add(v.data(), v.size() * sizeof(T));
  }
  const std::string& bytes() const { return out_; }

 private:
  static constexpr std::size_t kBlock = 1 << 15;
  void put(std::uint64_t u) {
    for (int b = 0; b < 8; ++b) out_.push_back(static_cast<char>((u >> (8 * b)) & 0xff));
  }
  std::string out_;
};

static_assert(std::endian::native == std::endian::little, "VTK files are written LittleEndian");

// One <DataArray> of a piece; its values go to the appended data.
struct VtkArray {
  const char* type;  // Float64, Int32, Int64, UInt8
  std::string name;
  int comps;
  std::size_t offset;
};

// The arrays of one piece, by section (PointData, Points, Verts, Lines, Polys, CellData).
class VtkPiece {
 public:
  explicit VtkPiece(AppendedData& data) : data_(data) {}
  template <class T>
  void add(const std::string& section, const char* type, const std::string& name, int comps,
           const std::vector<T>& values) {
    sections_[section].push_back({type, name, comps, data_.add(values)});
    if (std::find(order_.begin(), order_.end(), section) == order_.end()) order_.push_back(section);
  }
  void write(std::ostream& os, const std::string& attributes) const {
    os << "    <Piece " << attributes << ">\n";
    for (const std::string& section : order_) {
      os << "      <" << section;
      if (section == "PointData")
        os << " Scalars=\"radius\" Vectors=\"" << (has("velocity") ? "velocity" : "axis") << "\"";
      os << ">\n";
      for (const VtkArray& a : sections_.at(section)) {
        os << "        <DataArray type=\"" << a.type << "\"";
        if (!a.name.empty()) os << " Name=\"" << xml_escape(a.name) << "\"";
        os << " NumberOfComponents=\"" << a.comps << "\" format=\"appended\" offset=\"" << a.offset
           << "\"/>\n";
      }
      os << "      </" << section << ">\n";
    }
    os << "    </Piece>\n";
  }

 private:
  bool has(const std::string& name) const {
    for (const auto& [section, arrays] : sections_)
      for (const VtkArray& a : arrays)
        if (a.name == name) return true;
    return false;
  }
  AppendedData& data_;
  std::map<std::string, std::vector<VtkArray>> sections_;
  std::vector<std::string> order_;
};

// Values of the given elements, flattened.
std::vector<double> flat(const std::vector<std::size_t>& ids,
                         const std::function<void(std::vector<double>&, std::size_t)>& f) {
  std::vector<double> out;
  for (std::size_t i : ids) f(out, i);
  return out;
}

template <class T>
std::vector<T> pick(const std::vector<std::size_t>& ids, const std::vector<T>& all) {
  std::vector<T> out;
  out.reserve(ids.size());
  for (std::size_t i : ids) out.push_back(all[i]);
  return out;
}

// Cells as VTK wants them: connectivity (point ids) and offsets (one past each cell's end).
void add_cells(VtkPiece& piece, const char* section,
               const std::vector<std::vector<std::int64_t>>& cells) {
  if (cells.empty()) return;  // a section without cells is left out, as VTK itself writes it
  std::vector<std::int64_t> connectivity, offsets;
  for (const auto& c : cells) {
    connectivity.insert(connectivity.end(), c.begin(), c.end());
    offsets.push_back(static_cast<std::int64_t>(connectivity.size()));
  }
  piece.add(section, "Int64", "connectivity", 1, connectivity);
  piece.add(section, "Int64", "offsets", 1, offsets);
}

// Point ids (positions in `ids`) of each tube with at least two segments, in index order; tubes
// by ascending id.
std::vector<std::vector<std::int64_t>> tube_polylines(const Snapshot& s,
                                                      const std::vector<std::size_t>& ids) {
  std::map<std::int32_t, std::vector<std::pair<std::int32_t, std::int64_t>>> tubes;
  for (std::size_t p = 0; p < ids.size(); ++p)
    if (s.tube[ids[p]] >= 0)
      tubes[s.tube[ids[p]]].emplace_back(s.index[ids[p]], static_cast<std::int64_t>(p));
  std::vector<std::vector<std::int64_t>> lines;
  for (auto& [tube, members] : tubes) {
    if (members.size() < 2) continue;
    std::sort(members.begin(), members.end());
    std::vector<std::int64_t> line;
    for (const auto& m : members) line.push_back(m.second);
    lines.push_back(std::move(line));
  }
  return lines;
}

void write_vtk_document(std::ostream& os, const Snapshot& s, const std::string& what,
                        const std::string& piece_attributes, const VtkPiece& piece,
                        const AppendedData& data) {
  os << "<?xml version=\"1.0\"?>\n"
        "<!-- mdem snapshot, step "
     << s.step << ", time " << num(s.time_ps) << " ps; lengths in nm. " << what
     << "\n     Binary: appended raw data, zlib-compressed blocks (vtkZLibDataCompressor). -->\n"
        "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
        "header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">\n"
        "  <PolyData>\n"
        "    <FieldData>\n"
        "      <DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" "
        "format=\"ascii\">"
     << num(s.time_ps)
     << "</DataArray>\n"
        "      <DataArray type=\"Int64\" Name=\"Step\" NumberOfTuples=\"1\" format=\"ascii\">"
     << s.step
     << "</DataArray>\n"
        "    </FieldData>\n";
  piece.write(os, piece_attributes);
  os << "  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _";
  os.write(data.bytes().data(), static_cast<std::streamsize>(data.bytes().size()));
  os << "\n  </AppendedData>\n</VTKFile>\n";
}

constexpr int kDiscSides = 64;

}  // namespace

const char* species_of(std::int32_t kind, const char* grain) {
  switch (kind) {
    case 0:
      return "C";
    case 1:
      return "Si";
    case 2:
      return grain;
    default:
      return "X";
  }
}

const char* grain_species(const JobRecord& job) {
  if (job.kind != "compression") return "Au";
  try {
    const v1::JobSpec spec = spec::parse_json(job.spec_json);
    const v1::GrainMaterialKind m = spec.compression().material();
    return m == v1::GRAIN_MATERIAL_UNSPECIFIED || m == v1::GOLD ? "Au" : "X";
  } catch (const std::exception&) {
    return "X";  // a spec this mdem cannot read: no claim about the material
  }
}

void write_xyz_frame(std::ostream& os, const Snapshot& s, const char* grain) {
  const std::vector<std::size_t> ids = particle_ids(s);
  os << ids.size() << '\n' << xyz_header(s) << '\n';
  for (std::size_t i : ids) os << xyz_line(s, i, grain) << '\n';
}

void write_vtp(std::ostream& os, const Snapshot& s) {
  const std::vector<std::size_t> ids = particle_ids(s);
  const std::size_t n = ids.size();
  AppendedData data;
  VtkPiece piece(data);
  piece.add("PointData", "Float64", "orientation", 4, flat(ids, [&](auto& v, std::size_t i) {
              v.insert(v.end(), {s.q[i].x(), s.q[i].y(), s.q[i].z(), s.q[i].w()});
            }));
  piece.add("PointData", "Float64", "axis", 3, flat(ids, [&](auto& v, std::size_t i) {
              const Vec3 a = body_x_axis(s.q[i]);
              v.insert(v.end(), {a.x(), a.y(), a.z()});
            }));
  if (!s.v.empty())
    piece.add("PointData", "Float64", "velocity", 3, flat(ids, [&](auto& v, std::size_t i) {
                v.insert(v.end(), {s.v[i].x(), s.v[i].y(), s.v[i].z()});
              }));
  piece.add("PointData", "Float64", "radius", 1, pick(ids, s.radius));
  piece.add("PointData", "Int32", "kind", 1, pick(ids, s.kind));
  piece.add("PointData", "Int32", "tube", 1, pick(ids, s.tube));
  piece.add("PointData", "Int32", "index", 1, pick(ids, s.index));
  for (const auto& [name, values] : s.scalars)
    piece.add("PointData", "Float64", name, 1, pick(ids, values));
  piece.add("Points", "Float64", "position", 3, flat(ids, [&](auto& v, std::size_t i) {
              v.insert(v.end(), {s.x[i].x(), s.x[i].y(), s.x[i].z()});
            }));
  std::vector<std::vector<std::int64_t>> verts(n);
  for (std::size_t p = 0; p < n; ++p) verts[p] = {static_cast<std::int64_t>(p)};
  add_cells(piece, "Verts", verts);
  const auto lines = tube_polylines(s, ids);
  add_cells(piece, "Lines", lines);
  write_vtk_document(
      os, s,
      "\n     Points: element centres (platens are in the _walls files, bonds in the _bonds "
      "files).\n     orientation: the unit quaternion body -> world in x y z w order (w the scalar "
      "part, as\n     OVITO's Orientation). axis: body x in the world frame (a CNT segment's "
      "axis). "
      "velocity:\n     nm/ps. Verts: one per element. Lines: one polyline per tube through its "
      "segments in index order.",
      "NumberOfPoints=\"" + std::to_string(n) + "\" NumberOfVerts=\"" + std::to_string(n) +
          "\" NumberOfLines=\"" + std::to_string(lines.size()) +
          "\" NumberOfStrips=\"0\" NumberOfPolys=\"0\"",
      piece, data);
}

bool has_walls(const Snapshot& s) {
  for (std::size_t i = 0; i < s.size(); ++i)
    if (is_wall(s, i)) return true;
  return false;
}

void write_walls_vtp(std::ostream& os, const Snapshot& s) {
  AppendedData data;
  VtkPiece piece(data);
  std::vector<double> points, normals;
  std::vector<std::vector<std::int64_t>> polys;
  std::vector<std::int32_t> element;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!is_wall(s, i)) continue;
    const Vec3 u = s.q[i] * Vec3::UnitX(), w = s.q[i] * Vec3::UnitY(), nrm = s.q[i] * Vec3::UnitZ();
    std::vector<std::int64_t> poly;
    for (int k = 0; k < kDiscSides; ++k) {
      const double phi = 2 * M_PI * k / kDiscSides;
      const Vec3 p = s.x[i] + s.radius[i] * (std::cos(phi) * u + std::sin(phi) * w);
      poly.push_back(static_cast<std::int64_t>(points.size() / 3));
      points.insert(points.end(), {p.x(), p.y(), p.z()});
    }
    polys.push_back(std::move(poly));
    normals.insert(normals.end(), {nrm.x(), nrm.y(), nrm.z()});
    element.push_back(static_cast<std::int32_t>(i));
  }
  piece.add("Points", "Float64", "position", 3, points);
  add_cells(piece, "Polys", polys);
  piece.add("CellData", "Float64", "normal", 3, normals);
  piece.add("CellData", "Int32", "element", 1, element);
  write_vtk_document(
      os, s,
      "\n     Platens: one disc per platen (a " + std::to_string(kDiscSides) +
          "-gon of the platen's radius in its plane);\n     normal: towards the material; "
          "element: the platen's element number in the snapshot.",
      "NumberOfPoints=\"" + std::to_string(points.size() / 3) +
          "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"" +
          std::to_string(polys.size()) + "\"",
      piece, data);
}

void write_bonds_vtp(std::ostream& os, const Snapshot& s) {
  const std::vector<std::size_t> ids = particle_ids(s);
  std::vector<std::int64_t> point_of(s.size(), -1);
  for (std::size_t p = 0; p < ids.size(); ++p) point_of[ids[p]] = static_cast<std::int64_t>(p);
  AppendedData data;
  VtkPiece piece(data);
  std::vector<std::vector<std::int64_t>> lines;
  std::vector<std::int32_t> state;
  for (const SnapshotBond& b : s.bonds) {
    lines.push_back({point_of[b.i], point_of[b.j]});
    state.push_back(static_cast<std::int32_t>(b.state));
  }
  piece.add("Points", "Float64", "position", 3, flat(ids, [&](auto& v, std::size_t i) {
              v.insert(v.end(), {s.x[i].x(), s.x[i].y(), s.x[i].z()});
            }));
  add_cells(piece, "Lines", lines);
  piece.add("CellData", "Int32", "state", 1, state);
  write_vtk_document(
      os, s,
      "\n     Bonds: one line per bond between the centres of the elements it joins (the "
      "points of the\n     element file, in its order). state: 0 intact, 1 yielded (has flowed "
      "plastically), 2 broken.",
      "NumberOfPoints=\"" + std::to_string(ids.size()) + "\" NumberOfVerts=\"0\" NumberOfLines=\"" +
          std::to_string(lines.size()) + "\" NumberOfStrips=\"0\" NumberOfPolys=\"0\"",
      piece, data);
}

void write_pvd(std::ostream& os, const std::vector<PvdDataSet>& datasets) {
  os << "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
        "  <Collection>\n";
  for (const PvdDataSet& d : datasets)
    os << "    <DataSet timestep=\"" << num(d.time_ps) << "\" group=\"\" part=\"" << d.part
       << "\" name=\"" << xml_escape(d.name) << "\" file=\"" << xml_escape(d.file) << "\"/>\n";
  os << "  </Collection>\n</VTKFile>\n";
}

std::vector<std::string> csv_header(const std::vector<std::string>& columns) {
  std::vector<std::string> header = {"step", "time_ps"};
  for (const std::string& c : columns) {
    std::string name = c;
    for (int k = 2; std::find(header.begin(), header.end(), name) != header.end(); ++k)
      name = c + "_" + std::to_string(k);
    header.push_back(name);
  }
  return header;
}

void write_csv(std::ostream& os, const std::vector<std::string>& columns,
               const std::vector<SeriesFrame>& frames) {
  // A column repeating the frame's own time (compression's time_ps) is written once.
  std::vector<bool> keep(columns.size(), true);
  for (std::size_t c = 0; c < columns.size(); ++c)
    if (columns[c] == "time_ps")
      keep[c] = std::any_of(frames.begin(), frames.end(),
                            [&](const SeriesFrame& f) { return f.values[c] != f.time_ps; });
  std::vector<std::string> kept;
  for (std::size_t c = 0; c < columns.size(); ++c)
    if (keep[c]) kept.push_back(columns[c]);
  const std::vector<std::string> header = csv_header(kept);
  for (std::size_t k = 0; k < header.size(); ++k) os << (k ? "," : "") << csv_cell(header[k]);
  os << '\n';
  for (const SeriesFrame& f : frames) {
    std::string row = std::to_string(f.step) + ',' + num(f.time_ps);
    for (std::size_t c = 0; c < columns.size(); ++c) {
      if (!keep[c]) continue;
      row += ',';
      num(row, f.values[c]);
    }
    os << row << '\n';
  }
}

std::vector<std::string> export_xyz(const ResultsStore& store, const JobRecord& job,
                                    const std::string& path) {
  const std::size_t count = require_snapshots(store, job, "xyz");
  const char* grain = grain_species(job);
  std::ofstream os = open_out(path);
  for (std::size_t k = 0; k < count; ++k) write_xyz_frame(os, load_snapshot(store, job, k), grain);
  close_out(os, path);
  return {path};
}

std::string numbered(std::size_t k, std::size_t count) {
  std::string digits = std::to_string(k);
  const std::size_t width = std::max<std::size_t>(4, std::to_string(count - 1).size());
  return std::string(width - std::min(width, digits.size()), '0') + digits;
}

std::vector<std::string> export_vtk(const ResultsStore& store, const JobRecord& job,
                                    const std::string& pvd_path) {
  const fs::path pvd(pvd_path);
  if (pvd.extension() != ".pvd")
    throw UsageError("--out: '" + pvd_path + "' must end in .pvd for --format vtk");
  const std::size_t count = require_snapshots(store, job, "vtk");
  std::vector<PvdDataSet> datasets;
  std::vector<std::string> written;
  auto write = [&](const std::string& name, const Snapshot& s, int part, const char* label,
                   void (*writer)(std::ostream&, const Snapshot&)) {
    const std::string path = (pvd.parent_path() / name).string();
    std::ofstream os = open_out(path);
    writer(os, s);
    close_out(os, path);
    datasets.push_back({s.time_ps, part, label, name});
    written.push_back(path);
  };
  for (std::size_t k = 0; k < count; ++k) {
    const Snapshot s = load_snapshot(store, job, k);
    const std::string base = pvd.stem().string() + "_";
    write(base + numbered(k, count) + ".vtp", s, 0, "elements", write_vtp);
    if (!s.bonds.empty())
      write(base + "bonds_" + numbered(k, count) + ".vtp", s, 2, "bonds", write_bonds_vtp);
    if (has_walls(s))
      write(base + "walls_" + numbered(k, count) + ".vtp", s, 1, "platens", write_walls_vtp);
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
