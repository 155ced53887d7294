#pragma once
// The independent reader of mdem export's files, shared by the export tests: Python's standard
// library only (xml.etree, csv, struct, zlib and plain parsing of the extended-XYZ header). Run as
// `python3 reader.py MODE PATH` (MODE xyz, pvd, vtp, csv or svg), it prints JSON of what it read.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support.h"

namespace mdem::testing {

// Runs `python script args...` (each quoted) and parses the JSON it prints; a failed run or
// output that is not JSON fails the calling test.
inline nlohmann::json run_reader(const std::string& python, const std::string& script,
                                 const std::vector<std::string>& args) {
  std::string cmd = python + " '" + script + "'";
  for (const std::string& a : args) cmd += " '" + a + "'";
  const CliResult r = run_shell(cmd + " 2>&1");
  EXPECT_EQ(r.code, 0) << r.out;
  nlohmann::json j = nlohmann::json::parse(r.out, nullptr, false);
  EXPECT_FALSE(j.is_discarded()) << r.out;
  return j;
}

// The independent reader: Python standard library only. Prints JSON of what it read.
inline constexpr const char* kExportReader = R"py(
import csv, json, os, struct, sys, zlib
import xml.etree.ElementTree as ET

def read_xyz(path):
    with open(path) as f:
        lines = f.read().split('\n')
    frames, i = [], 0
    while i < len(lines) and lines[i].strip():
        n = int(lines[i])
        header = dict(tok.split('=', 1) for tok in lines[i + 1].split())
        spec = header['Properties'].split(':')
        props = [(spec[k], spec[k + 1], int(spec[k + 2])) for k in range(0, len(spec), 3)]
        cols = {name: [] for name, _, _ in props}
        for row in lines[i + 2:i + 2 + n]:
            toks, c = row.split(), 0
            for name, typ, cnt in props:
                conv = {'S': str, 'R': float, 'I': int}[typ]
                vals = [conv(t) for t in toks[c:c + cnt]]
                c += cnt
                cols[name].append(vals if cnt > 1 else vals[0])
            assert c == len(toks), row
        frames.append({'n': n, 'time': float(header['Time']), 'step': int(header['Step']),
                       'properties': [list(p) for p in props], 'columns': cols})
        i += 2 + n
    return frames

# Binary VTK XML: the XML up to <AppendedData>, then raw data after '_'; each array at its offset
# as vtkZLibDataCompressor writes it (UInt64 header: blocks, block size, last partial size, the
# compressed sizes; then the zlib blocks), decoded here with zlib and struct.
TYPES = {'Float64': 'd', 'Int64': 'q', 'Int32': 'i', 'UInt8': 'B'}

def read_array(da, data):
    comps = int(da.get('NumberOfComponents', '1'))
    if da.get('format') == 'ascii':
        conv = float if da.get('type').startswith('Float') else int
        vals = [conv(t) for t in (da.text or '').split()]
    else:
        assert da.get('format') == 'appended', da.attrib
        at = int(da.get('offset'))
        blocks, block, last = struct.unpack_from('<3Q', data, at)
        sizes = struct.unpack_from('<%dQ' % blocks, data, at + 24)
        at += 24 + 8 * blocks
        raw = b''
        for k, size in enumerate(sizes):
            chunk = zlib.decompress(data[at:at + size])
            want = last if (k == blocks - 1 and last) else block
            assert len(chunk) == want, (len(chunk), want)
            raw += chunk
            at += size
        fmt = TYPES[da.get('type')]
        vals = list(struct.unpack('<%d%s' % (len(raw) // struct.calcsize(fmt), fmt), raw))
    return [vals[k:k + comps] for k in range(0, len(vals), comps)] if comps > 1 else vals

def read_vtp(path):
    with open(path, 'rb') as f:
        content = f.read()
    head, sep, rest = content.partition(b'<AppendedData encoding="raw">')
    assert sep, 'no appended data'
    data = rest[rest.index(b'_') + 1:]
    root = ET.fromstring(head + b'</VTKFile>')
    assert root.get('type') == 'PolyData'
    assert root.get('compressor') == 'vtkZLibDataCompressor'
    piece = root.find('PolyData/Piece')
    def cells(tag):
        el = piece.find(tag)
        conn = read_array(el.find("DataArray[@Name='connectivity']"), data)
        offsets = read_array(el.find("DataArray[@Name='offsets']"), data)
        out, start = [], 0
        for o in offsets:
            out.append(conn[start:o])
            start = o
        return out
    time = root.find("PolyData/FieldData/DataArray[@Name='TimeValue']")
    def section(tag):
        el = piece.find(tag)
        return {} if el is None else {da.get('Name'): read_array(da, data)
                                      for da in el.findall('DataArray')}
    return {'n_points': int(piece.get('NumberOfPoints')),
            'n_lines': int(piece.get('NumberOfLines')),
            'n_polys': int(piece.get('NumberOfPolys')),
            'time': float(time.text),
            'points': read_array(piece.find('Points/DataArray'), data),
            'point_data': section('PointData'),
            'cell_data': section('CellData'),
            'lines': cells('Lines') if piece.find('Lines') is not None else [],
            'polys': cells('Polys') if piece.find('Polys') is not None else []}

def read_pvd(path):
    root = ET.parse(path).getroot()
    assert root.get('type') == 'Collection'
    sets = [{'timestep': float(d.get('timestep')), 'file': d.get('file'),
             'part': int(d.get('part'))}
            for d in root.find('Collection').findall('DataSet')]
    where = os.path.dirname(path)
    return {'datasets': sets, 'pieces': [read_vtp(os.path.join(where, d['file'])) for d in sets]}

def read_csv(path):
    with open(path, newline='') as f:
        rows = list(csv.reader(f))
    return {'header': rows[0], 'rows': [[float(x) for x in r] for r in rows[1:]]}

def read_svg(path):
    root = ET.parse(path).getroot()
    tags = [el.tag.split('}')[-1] for el in root.iter()]
    return {'root': root.tag.split('}')[-1], 'paths': tags.count('path'),
            'polylines': tags.count('polyline')}

readers = {'xyz': read_xyz, 'pvd': read_pvd, 'vtp': read_vtp, 'csv': read_csv, 'svg': read_svg}
print(json.dumps(readers[sys.argv[1]](sys.argv[2])))
)py";

}  // namespace mdem::testing
