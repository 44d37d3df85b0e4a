#include "traces/gen/Mesh.hpp"

#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "traces/InputFile.hpp"

namespace oit::gen {

namespace {

// Reads text lines from a plain or gzip-compressed file (gzopen reads both) and
// numbers them, so every error can say "file:line: ...".
class LineReader {
 public:
  // Longer lines are an error: memory stays bounded whatever the file holds.
  static constexpr size_t kMaxLineBytes = size_t{1} << 20;

  explicit LineReader(const std::string& path) : path_(path) {
    // A regular file only (a FIFO would block, a device never end), opened
    // without blocking; zlib then reads it through the descriptor.
    InputFile in = openInputFile(path);
    if (!in && in.error)
      throw std::runtime_error(fmt::format("cannot open mesh file '{}': {}", path, std::strerror(in.error)));
    if (!in) throw std::runtime_error(fmt::format("mesh file '{}': {}", path, in.problem));
    errno = 0;
    file_ = gzdopen(in.fd.get(), "rb");
    if (!file_)
      throw std::runtime_error(fmt::format("cannot open mesh file '{}': {}", path,
                                           errno ? std::strerror(errno) : "out of memory"));
    in.fd.release();  // gzclose closes it
    gzbuffer(file_, 1 << 17);
  }
  ~LineReader() { gzclose(file_); }
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  // The next line without its end-of-line characters; false at the end of the file.
  bool next(std::string& line) {
    line.clear();
    char buf[8192];
    for (;;) {
      if (!gzgets(file_, buf, sizeof buf)) {
        int err = Z_OK;
        const char* msg = gzerror(file_, &err);
        if (err != Z_OK && err != Z_STREAM_END) {
          const std::string what = err == Z_ERRNO ? std::strerror(errno) : msg;
          throw std::runtime_error(
              fmt::format("{}:{}: read error: {}", path_, line_no_ + 1, what));
        }
        if (line.empty()) return false;
        break;
      }
      const size_t n = std::strlen(buf);
      line.append(buf, n);
      if (line.size() > kMaxLineBytes)
        throw std::runtime_error(fmt::format("{}:{}: line is longer than {} bytes: not a text mesh file?", path_,
                                             line_no_ + 1, kMaxLineBytes));
      if (n > 0 && buf[n - 1] == '\n') break;
    }
    ++line_no_;
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    return true;
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(fmt::format("{}:{}: {}", path_, line_no_, what));
  }
  uint64_t lineNumber() const { return line_no_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  gzFile file_ = nullptr;
  uint64_t line_no_ = 0;
};

// Whitespace-separated tokens of one line.
class Tokens {
 public:
  explicit Tokens(std::string_view s) : rest_(s) {}
  std::optional<std::string_view> next() {
    size_t b = rest_.find_first_not_of(" \t\v\f");
    if (b == std::string_view::npos) {
      rest_ = {};
      return std::nullopt;
    }
    size_t e = rest_.find_first_of(" \t\v\f", b);
    std::string_view tok = rest_.substr(b, e == std::string_view::npos ? rest_.size() - b : e - b);
    rest_ = e == std::string_view::npos ? std::string_view{} : rest_.substr(e);
    return tok;
  }

 private:
  std::string_view rest_;
};

std::string_view stripComment(std::string_view line) {
  size_t h = line.find('#');
  return h == std::string_view::npos ? line : line.substr(0, h);
}

bool isBlank(std::string_view s) { return s.find_first_not_of(" \t\v\f") == std::string_view::npos; }

// Locale-independent number parsing (from_chars), with the file and line on failure.
float parseCoord(const LineReader& in, std::string_view tok, const char* what) {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  float v = 0;
  auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
  if (ec == std::errc::result_out_of_range) in.fail(fmt::format("{} '{}' is out of float range", what, tok));
  if (ec != std::errc() || p != tok.data() + tok.size())
    in.fail(fmt::format("{} '{}' is not a number", what, tok));
  if (!std::isfinite(v)) in.fail(fmt::format("{} '{}' is not a finite number", what, tok));
  return v;
}

int64_t parseInt(const LineReader& in, std::string_view tok, const char* what) {
  if (!tok.empty() && tok.front() == '+') tok.remove_prefix(1);
  int64_t v = 0;
  auto [p, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
  if (ec != std::errc() || p != tok.data() + tok.size())
    in.fail(fmt::format("{} '{}' is not an integer", what, tok));
  return v;
}

Vec3 parseXyz(const LineReader& in, Tokens& t) {
  float c[3];
  for (int i = 0; i < 3; ++i) {
    auto tok = t.next();
    if (!tok) in.fail("vertex needs three coordinates x y z");
    c[i] = parseCoord(in, *tok, "vertex coordinate");
  }
  return {c[0], c[1], c[2]};
}

void addFan(Mesh& m, const std::vector<uint32_t>& poly) {
  for (size_t i = 1; i + 1 < poly.size(); ++i) m.triangles.push_back({poly[0], poly[i], poly[i + 1]});
}

std::string lower(std::string_view s) {
  std::string r(s);
  for (char& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

bool endsWith(std::string_view s, std::string_view suffix) {
  return s.size() >= suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

}  // namespace

Mesh loadObj(const std::string& path) {
  LineReader in(path);
  Mesh m;
  m.source = path;
  std::string line;
  std::vector<uint32_t> poly;
  while (in.next(line)) {
    Tokens t(stripComment(line));
    auto kw = t.next();
    if (!kw) continue;
    if (*kw == "v") {
      m.positions.push_back(parseXyz(in, t));  // an optional w is ignored
    } else if (*kw == "f") {
      poly.clear();
      while (auto tok = t.next()) {
        // "v", "v/vt", "v//vn" or "v/vt/vn": only the position index matters.
        std::string_view idx = tok->substr(0, tok->find('/'));
        int64_t i = parseInt(in, idx, "face index");
        const int64_t count = static_cast<int64_t>(m.positions.size());
        if (i == 0) in.fail("face index 0 is invalid (OBJ indices start at 1)");
        int64_t k = i > 0 ? i - 1 : count + i;  // negative: relative to the last vertex
        if (k < 0 || k >= count)
          in.fail(fmt::format("face index {} refers to a vertex not defined yet ({} so far)", i,
                              count));
        poly.push_back(static_cast<uint32_t>(k));
      }
      if (poly.size() < 3) in.fail(fmt::format("face has {} vertices, needs at least 3", poly.size()));
      addFan(m, poly);
    }
    // vt, vn, g, o, s, usemtl, mtllib, l, p and the rest do not shape the surface.
  }
  return m;
}

Mesh loadOff(const std::string& path) {
  LineReader in(path);
  Mesh m;
  m.source = path;
  std::string line;
  // The next line with content, comments removed; nullopt at the end of the file.
  auto content = [&]() -> std::optional<std::string_view> {
    while (in.next(line)) {
      std::string_view s = stripComment(line);
      if (!isBlank(s)) return s;
    }
    return std::nullopt;
  };
  auto early = [&](const std::string& what) { in.fail("file ends early: expected " + what); };

  auto header = content();
  if (!header) early("the OFF header");
  Tokens head(*header);
  std::string_view magic = *head.next();
  // OFF with optional ST/C/N prefixes (texture, colour, normals: extra per-vertex
  // numbers we skip); 4OFF and nOFF have other dimensions.
  if (!endsWith(magic, "OFF")) in.fail(fmt::format("not an OFF file: header is '{}', expected OFF", magic));
  if (magic.find('4') != std::string_view::npos || magic.find('n') != std::string_view::npos)
    in.fail(fmt::format("'{}' files are not 3-dimensional; only OFF is supported", magic));
  std::optional<std::string_view> first = head.next();
  if (first && *first == "BINARY") in.fail("binary OFF is not supported, only ASCII OFF");
  std::optional<std::string_view> counts_line = first ? std::nullopt : content();
  if (!first && !counts_line) early("vertex and face counts");
  Tokens counts = first ? head : Tokens(*counts_line);
  int64_t nv = -1, nf = -1;
  if (auto tok = first ? first : counts.next()) nv = parseInt(in, *tok, "vertex count");
  if (auto tok = counts.next()) nf = parseInt(in, *tok, "face count");
  if (nv < 0 || nf < 0) in.fail("expected 'vertices faces edges' counts");

  m.positions.reserve(static_cast<size_t>(std::min<int64_t>(nv, 1 << 24)));
  for (int64_t i = 0; i < nv; ++i) {
    auto s = content();
    if (!s) early(fmt::format("{} vertices, got {}", nv, i));
    Tokens t(*s);
    m.positions.push_back(parseXyz(in, t));
  }
  std::vector<uint32_t> poly;
  for (int64_t f = 0; f < nf; ++f) {
    auto s = content();
    if (!s) early(fmt::format("{} faces, got {}", nf, f));
    Tokens t(*s);
    int64_t n = parseInt(in, *t.next(), "face vertex count");
    if (n < 3) in.fail(fmt::format("face has {} vertices, needs at least 3", n));
    poly.clear();
    for (int64_t k = 0; k < n; ++k) {
      auto tok = t.next();
      if (!tok) in.fail(fmt::format("face lists {} vertices but gives {}", n, k));
      int64_t i = parseInt(in, *tok, "face index");
      if (i < 0 || i >= nv) in.fail(fmt::format("face index {} is outside 0..{}", i, nv - 1));
      poly.push_back(static_cast<uint32_t>(i));
    }
    addFan(m, poly);  // any colour after the indices is ignored
  }
  return m;
}

Mesh loadPly(const std::string& path) {
  LineReader in(path);
  Mesh m;
  m.source = path;
  std::string line;

  struct Property {
    std::string name;
    bool list = false;
  };
  struct Element {
    std::string name;
    int64_t count = 0;
    std::vector<Property> props;
  };
  std::vector<Element> elements;

  if (!in.next(line) || line != "ply") in.fail("not a PLY file: the first line must be 'ply'");
  bool have_format = false;
  for (;;) {
    if (!in.next(line)) in.fail("file ends inside the PLY header (no end_header)");
    Tokens t(line);
    auto kw = t.next();
    if (!kw || *kw == "comment" || *kw == "obj_info") continue;
    if (*kw == "end_header") break;
    if (*kw == "format") {
      auto fmt_name = t.next();
      if (!fmt_name) in.fail("format line names no format");
      if (*fmt_name != "ascii")
        in.fail(fmt::format("only ASCII PLY is supported; this file is {}", *fmt_name));
      have_format = true;
    } else if (*kw == "element") {
      auto name = t.next(), count = t.next();
      if (!name || !count) in.fail("element line needs a name and a count");
      int64_t n = parseInt(in, *count, "element count");
      if (n < 0) in.fail(fmt::format("element count {} is negative", n));
      elements.push_back({std::string(*name), n, {}});
    } else if (*kw == "property") {
      if (elements.empty()) in.fail("property before any element");
      auto type = t.next();
      if (!type) in.fail("property line names no type");
      Property p;
      if (*type == "list") {
        p.list = true;
        if (!t.next() || !t.next()) in.fail("list property needs a count type and an item type");
      }
      auto name = t.next();
      if (!name) in.fail("property line names no property");
      p.name = std::string(*name);
      elements.back().props.push_back(p);
    } else {
      in.fail(fmt::format("unknown PLY header keyword '{}'", *kw));
    }
  }
  if (!have_format) in.fail("PLY header has no format line");

  std::vector<uint32_t> poly;
  int64_t nv = -1;
  for (const Element& el : elements) {
    int xi = -1, yi = -1, zi = -1, fi = -1;
    for (size_t i = 0; i < el.props.size(); ++i) {
      const Property& p = el.props[i];
      const int idx = static_cast<int>(i);
      if (!p.list && p.name == "x") xi = idx;
      if (!p.list && p.name == "y") yi = idx;
      if (!p.list && p.name == "z") zi = idx;
      if (p.list && (p.name == "vertex_indices" || p.name == "vertex_index")) fi = idx;
    }
    const bool is_vertex = el.name == "vertex", is_face = el.name == "face";
    if (is_vertex && (xi < 0 || yi < 0 || zi < 0)) in.fail("PLY vertex element lacks an x, y or z property");
    if (is_face && fi < 0) in.fail("PLY face element lacks a vertex_indices list");
    if (is_face && nv < 0) in.fail("PLY face element comes before the vertex element");
    if (is_vertex) {
      nv = el.count;
      m.positions.reserve(static_cast<size_t>(std::min<int64_t>(nv, 1 << 24)));
    }

    for (int64_t r = 0; r < el.count; ++r) {
      if (!in.next(line))
        in.fail(fmt::format("file ends early: expected {} '{}' elements, got {}", el.count, el.name, r));
      if (!is_vertex && !is_face) continue;  // other elements (edges, materials) are skipped
      Tokens t(line);
      Vec3 pos;
      poly.clear();
      for (size_t i = 0; i < el.props.size(); ++i) {
        const Property& p = el.props[i];
        const int idx = static_cast<int>(i);
        auto tok = t.next();
        if (!tok) in.fail(fmt::format("'{}' element has no value for property '{}'", el.name, p.name));
        if (!p.list) {
          if (idx == xi) pos.x = parseCoord(in, *tok, "x");
          if (idx == yi) pos.y = parseCoord(in, *tok, "y");
          if (idx == zi) pos.z = parseCoord(in, *tok, "z");
          continue;
        }
        int64_t n = parseInt(in, *tok, "list length");
        if (n < 0) in.fail(fmt::format("list length {} is negative", n));
        for (int64_t k = 0; k < n; ++k) {
          auto item = t.next();
          if (!item) in.fail(fmt::format("list '{}' announces {} items but gives {}", p.name, n, k));
          if (idx != fi) continue;
          int64_t vi = parseInt(in, *item, "face index");
          if (vi < 0 || vi >= nv) in.fail(fmt::format("face index {} is outside 0..{}", vi, nv - 1));
          poly.push_back(static_cast<uint32_t>(vi));
        }
        if (idx == fi && n < 3) in.fail(fmt::format("face has {} vertices, needs at least 3", n));
      }
      if (is_vertex) m.positions.push_back(pos);
      else addFan(m, poly);
    }
  }
  if (nv < 0) in.fail("PLY file has no vertex element");
  return m;
}

Mesh loadMesh(const std::string& path) {
  std::string name = lower(path);
  if (endsWith(name, ".gz")) name.resize(name.size() - 3);
  Mesh m;
  if (endsWith(name, ".obj")) m = loadObj(path);
  else if (endsWith(name, ".off")) m = loadOff(path);
  else if (endsWith(name, ".ply")) m = loadPly(path);
  else
    throw std::runtime_error(fmt::format(
        "mesh file '{}': unknown format; expected .obj, .off or .ply (optionally .gz)", path));
  if (m.triangles.empty()) throw std::runtime_error(fmt::format("mesh file '{}' has no faces", path));
  return m;
}

MeshBounds meshBounds(const Mesh& mesh) {
  MeshBounds b;
  constexpr float inf = std::numeric_limits<float>::infinity();
  b.min = {inf, inf, inf};
  b.max = {-inf, -inf, -inf};
  std::vector<bool> used(mesh.positions.size());
  for (const auto& t : mesh.triangles)
    for (uint32_t i : t) used[i] = true;
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    if (!used[i]) continue;
    const Vec3& p = mesh.positions[i];
    b.min = {std::min(b.min.x, p.x), std::min(b.min.y, p.y), std::min(b.min.z, p.z)};
    b.max = {std::max(b.max.x, p.x), std::max(b.max.y, p.y), std::max(b.max.z, p.z)};
  }
  if (b.min.x > b.max.x) return MeshBounds{};  // no triangles
  b.centre = (b.min + b.max) * 0.5f;
  // Halving first gives the same bits unless the sum overflows (|coordinates| > 1.7e38).
  if (!std::isfinite(b.centre.x) || !std::isfinite(b.centre.y) || !std::isfinite(b.centre.z))
    b.centre = b.min * 0.5f + b.max * 0.5f;
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    if (used[i]) b.radius = std::max(b.radius, length(mesh.positions[i] - b.centre));
  // fp32 squares overflow beyond about 1e19 (radius +Inf) and underflow below
  // about 1e-19 (radius 0): measure such meshes in double. The fp32 result is
  // kept otherwise, so ordinary meshes give the same bits as always.
  if (!std::isfinite(b.radius) || b.radius == 0) {
    double r2 = 0;
    for (size_t i = 0; i < mesh.positions.size(); ++i) {
      if (!used[i]) continue;
      const double dx = double(mesh.positions[i].x) - b.centre.x, dy = double(mesh.positions[i].y) - b.centre.y,
                   dz = double(mesh.positions[i].z) - b.centre.z;
      r2 = std::max(r2, dx * dx + dy * dy + dz * dz);
    }
    b.radius = static_cast<float>(std::sqrt(r2));  // +Inf only beyond fp32's range: addMesh refuses it
  }
  return b;
}

// Where scripts/install-meshes.sh keeps the meshes of libcgal-demo's data.tar.gz.
constexpr const char* kCgalMeshDir = "/var/cache/oitsim/meshes/cgal";

// Add a row to make another installed mesh available by name.
const std::vector<NamedMesh>& namedMeshes() {
  static const std::vector<NamedMesh> table = {
      {"bunny", "/usr/share/glmark2/models/bunny.obj", "glmark2-data",
       "Stanford bunny, 69,666 triangles (glmark2's copy)"},
      {"elephant", std::string(kCgalMeshDir) + "/refined_elephant.off", "libcgal-demo",
       "elephant, 88,928 triangles"},
      {"bunny-cgal", std::string(kCgalMeshDir) + "/bunny00.off", "libcgal-demo",
       "Stanford bunny, 75,408 triangles (CGAL's copy)"},
      {"armadillo", std::string(kCgalMeshDir) + "/armadillo.off", "libcgal-demo",
       "Stanford armadillo, 52,000 triangles"},
      {"diplodocus", std::string(kCgalMeshDir) + "/diplodocus.off", "libcgal-demo",
       "diplodocus, 47,960 triangles"},
      {"man", std::string(kCgalMeshDir) + "/man.off", "libcgal-demo",
       "standing man, 34,986 triangles"},
      {"mannequin", std::string(kCgalMeshDir) + "/mannequin-devil.off", "libcgal-demo",
       "mannequin, 25,888 triangles"},
      {"dragon", std::string(kCgalMeshDir) + "/ChineseDragon-10kv.off", "libcgal-demo",
       "Chinese dragon, 19,994 triangles"},
      {"camel", std::string(kCgalMeshDir) + "/camel.off", "libcgal-demo",
       "camel, 19,536 triangles"},
      {"lion", std::string(kCgalMeshDir) + "/lion.off", "libcgal-demo",
       "lion, 14,859 triangles"},
      {"bull", std::string(kCgalMeshDir) + "/bull.off", "libcgal-demo",
       "bull, 12,396 triangles"},
      {"homer", std::string(kCgalMeshDir) + "/homer.off", "libcgal-demo",
       "Homer Simpson, 9,856 triangles"},
      {"cow", std::string(kCgalMeshDir) + "/cow.off", "libcgal-demo",
       "cow, 5,804 triangles"},
      {"triceratops", std::string(kCgalMeshDir) + "/triceratops.off", "libcgal-demo",
       "triceratops, 5,660 triangles"},
  };
  return table;
}

const NamedMesh* findNamedMesh(std::string_view name, const std::vector<NamedMesh>& table) {
  for (const NamedMesh& m : table)
    if (m.name == name) return &m;
  return nullptr;
}

std::string meshInstallHint(const NamedMesh& m) {
  // libcgal-demo's meshes sit in a tarball inside the package, which also pulls in
  // Qt: the script unpacks just the meshes.
  if (m.package == "libcgal-demo") return "scripts/install-meshes.sh unpacks them from it";
  return "apt-get install " + m.package;
}

bool fileReadable(const std::string& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec) && ::access(path.c_str(), R_OK) == 0;
}

std::string resolveMeshPath(const std::string& name_or_path, const std::vector<NamedMesh>& table) {
  if (const NamedMesh* m = findNamedMesh(name_or_path, table)) {
    if (!fileReadable(m->path))
      throw std::runtime_error(fmt::format(
          "mesh '{}' needs {}, which is not installed: it comes with the Debian package {} ({})",
          m->name, m->path, m->package, meshInstallHint(*m)));
    return m->path;
  }
  std::error_code ec;
  if (std::filesystem::exists(name_or_path, ec)) return name_or_path;  // loadMesh explains further
  std::string names;
  for (const NamedMesh& m : table) names += (names.empty() ? "" : ", ") + m.name;
  throw std::runtime_error(fmt::format(
      "mesh '{}' is neither an existing file nor a known mesh name (known names: {})",
      name_or_path, names));
}

std::string meshDisplayName(const std::string& name_or_path) {
  if (findNamedMesh(name_or_path)) return name_or_path;
  std::string base = std::filesystem::path(name_or_path).filename().string();
  if (endsWith(lower(base), ".gz")) base.resize(base.size() - 3);
  size_t dot = base.rfind('.');
  if (dot != std::string::npos && dot > 0) base.resize(dot);
  return base.empty() ? std::string("mesh") : base;
}

}  // namespace oit::gen
