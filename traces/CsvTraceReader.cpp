// CSV form of trace format v1 (FORMAT.md, "CSV form"): a two-pass streaming
// reader (pass 1 builds the draw table and count, pass 2 hands out batches;
// memory: one batch, one read buffer and the draw table). The writer is
// CsvTraceWriter.cpp.
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string_view>
#include <unordered_map>

#include "traces/CsvTokens.hpp"
#include "traces/DrawStateTable.hpp"
#include "traces/InputFile.hpp"
#include "traces/TraceBackends.hpp"
#include "traces/TraceFormat.hpp"
#include "traces/TraceRules.hpp"

namespace oit::detail {

namespace fv = format_v1;

namespace {

constexpr std::string_view kCsvColumnLine = "draw,prim,x,y,z,r,g,b,a,opaque";
constexpr size_t kColumns = 10;
constexpr const char* kColumnNames[kColumns] = {"draw", "prim", "x", "y", "z",
                                                "r",    "g",    "b", "a", "opaque"};
enum Col : size_t { kDraw, kPrim, kX, kY, kZ, kR, kG, kB, kA, kOpaque };

std::string_view trim(std::string_view s) {
  while (!s.empty() && isCsvBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && isCsvBlank(s.back())) s.remove_suffix(1);
  return s;
}

bool allBlank(std::string_view s) { return trim(s).empty(); }

// Shows the bytes a terminal would not print as text as \xNN: control bytes,
// DEL, C1 controls (U+0080-U+009F) and every byte >= 0x80 that is not part of
// a well-formed UTF-8 character (a binary or gzip file read as CSV). The text
// of a bad field is quoted in the message, and a NUL in it would end the
// message wherever what() is printed as a C string.
std::string printable(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    const size_t n = c < 0x80 ? 1 : utf8CharBytes(s, i);
    const bool c1 = n == 2 && c == 0xC2 && static_cast<unsigned char>(s[i + 1]) < 0xA0;
    if (c < 0x20 || c == 0x7f || n == 0 || c1) {
      out += fmt::format("\\x{:02x}", c);
      ++i;
    } else {
      out.append(s.substr(i, n));
      i += n;
    }
  }
  return out;
}

// Reads lines from one open file descriptor (read(), no mapping) through a
// fixed buffer, and keeps track of where each starts. A line longer than
// fv::kMaxCsvLineBytes is an error naming it, so a file without line ends (or
// with a runaway line) costs no more memory than any other.
class LineReader {
 public:
  LineReader(std::string path, FileDescriptor fd)
      : path_(std::move(path)), fd_(std::move(fd)), buf_(std::make_unique_for_overwrite<char[]>(kBufBytes)) {}
  // False at end of file. Strips a trailing CR (files edited on Windows) and a
  // leading UTF-8 byte order mark.
  bool next() {
    size_t nl = find();
    while (nl == kNone) {
      if (eof_) {
        if (begin_ == end_) return false;
        nl = end_;  // the last line has no line end
        break;
      }
      fill();
      nl = find();
    }
    const size_t len = nl - begin_;
    if (len > fv::kMaxCsvLineBytes) tooLong();
    offset_ = next_offset_;
    ++number_;
    line_ = std::string_view(buf_.get() + begin_, len);
    const size_t used = nl < end_ ? len + 1 : len;
    begin_ += used;
    next_offset_ += used;
    if (!line_.empty() && line_.back() == '\r') line_.remove_suffix(1);
    if (offset_ == 0 && line_.starts_with("\xEF\xBB\xBF")) {  // UTF-8 BOM from some editors
      line_.remove_prefix(3);
      offset_ = 3;
    }
    return true;
  }
  // Reading goes on at `offset`, the start of line `line_number` + 1.
  void seek(uint64_t offset, uint64_t line_number) {
    begin_ = end_ = 0;
    eof_ = false;
    file_pos_ = offset;
    next_offset_ = offset;
    number_ = line_number;
  }
  // Up to n bytes from the start of the file (does not move the reader).
  std::string_view peek(size_t n) {
    head_.resize(n);
    const ssize_t k = readAt(head_.data(), n, 0);
    head_.resize(static_cast<size_t>(k));
    return head_;
  }
  std::string_view line() const { return line_; }
  uint64_t number() const { return number_; }  // 1-based number of the current line
  uint64_t offset() const { return offset_; }  // byte offset of the current line
  uint64_t nextOffset() const { return next_offset_; }
  int fd() const { return fd_.get(); }

 private:
  static constexpr size_t kChunk = size_t{1} << 20;
  static constexpr size_t kNone = ~size_t{0};
  static constexpr size_t kBufBytes = fv::kMaxCsvLineBytes + kChunk;
  size_t find() const {
    const void* p = std::memchr(buf_.get() + begin_, '\n', end_ - begin_);
    return p ? static_cast<size_t>(static_cast<const char*>(p) - buf_.get()) : kNone;
  }
  // Moves the unread bytes to the front and reads more after them.
  void fill() {
    if (end_ - begin_ > fv::kMaxCsvLineBytes) tooLong();
    std::memmove(buf_.get(), buf_.get() + begin_, end_ - begin_);
    end_ -= begin_;
    begin_ = 0;
    const ssize_t k = readAt(buf_.get() + end_, kBufBytes - end_, file_pos_);
    if (k == 0) eof_ = true;
    end_ += static_cast<size_t>(k);
    file_pos_ += static_cast<uint64_t>(k);
  }
  ssize_t readAt(char* dst, size_t n, uint64_t at) {
    for (;;) {
      const ssize_t k = ::pread(fd_.get(), dst, n, static_cast<off_t>(at));
      if (k >= 0) return k;
      if (errno != EINTR) throw TraceError(path_, fmt::format("read error: {}", std::strerror(errno)));
    }
  }
  // The line after the current one (the one being read) is too long.
  [[noreturn]] void tooLong() const {
    throw TraceError::inCsv(path_, number_ + 1, next_offset_, std::nullopt, "",
                            fmt::format("line is longer than {} bytes, the most a CSV trace line may have "
                                        "(FORMAT.md section 8.2); is this a CSV trace?",
                                        fv::kMaxCsvLineBytes));
  }

  std::string path_;
  FileDescriptor fd_;
  // Not zero-filled: only bytes read into it are looked at, and zeroing it
  // would fault in all of its pages at every open (the CSV fuzzer's inputs
  // spent 98 % of their time there).
  std::unique_ptr<char[]> buf_;
  std::string head_;
  size_t begin_ = 0, end_ = 0;  // unread bytes of buf_
  bool eof_ = false;
  uint64_t file_pos_ = 0;     // file offset of buf_[end_]
  std::string_view line_;
  uint64_t number_ = 0;
  uint64_t offset_ = 0;
  uint64_t next_offset_ = 0;
};

struct CsvDraw {
  size_t index;          // into TraceHeader::draws
  bool declared;         // listed by a "# draw" comment line
  uint64_t where_line;   // the comment line, or the draw's first row
};

class CsvReader final : public FragmentSource {
 public:
  CsvReader(const std::string& path, const OpenOptions& opts);
  const TraceHeader& header() const override { return header_; }
  const std::string& path() const override { return path_; }
  uint64_t position() const override { return pos_; }
  void rewind() override {
    in_.seek(data_offset_, data_line_ - 1);
    pos_ = 0;
  }
  std::span<const Fragment> next() override;

 private:
  [[noreturn]] void fail(uint64_t byte_offset, std::optional<uint64_t> record,
                         std::string field, const std::string& msg) const {
    throw TraceError::inCsv(path_, in_.number(), byte_offset, record, printable(field), printable(msg));
  }
  // A binary trace or a gzip file named .csv: say so rather than quote its bytes.
  void refuseBinaryForms();
  void parseMetadata(std::string_view line);
  // The draw that would be entry kMaxDraws + 1 of the table.
  std::string tooManyDraws(uint32_t id) const {
    return fmt::format("draw {} would be draw number {} of the trace: at most {} distinct draws allowed "
                       "(draw_count, FORMAT.md section 2.1)",
                       id, header_.draws.size() + 1, fv::kMaxDraws);
  }
  // Parses the current line as record `record`; in pass 1 unknown draws join the table.
  Fragment parseRow(uint64_t record, bool first_pass);
  // The next line that is neither blank nor a comment (the column line, then
  // the data lines); comment lines go to parseMetadata. False at end of file.
  bool nextContentLine();

  std::string path_;
  TraceHeader header_;
  LineReader in_;
  std::optional<uint32_t> meta_width_, meta_height_;
  bool meta_version_ = false, meta_camera_ = false, meta_encoding_ = false;
  std::unordered_map<uint32_t, CsvDraw> draws_;
  RecordRules rules_;
  uint64_t data_offset_ = 0;  // first byte after the column line
  uint64_t data_line_ = 0;    // line number of the first line after the column line
  uint64_t pos_ = 0;
  size_t batch_;
  std::vector<Fragment> buf_;
  uint64_t size_at_open_ = 0;
};

// Non-blocking open of a regular file only: a FIFO, a device or a folder is
// refused before anything is read. The one descriptor serves both passes.
FileDescriptor openCsvFile(const std::string& path) {
  InputFile f = openInputFile(path);
  if (!f) throw TraceError(path, f.problem);
  return std::move(f.fd);
}

CsvReader::CsvReader(const std::string& path, const OpenOptions& opts)
    : path_(path), in_(path, openCsvFile(path)), batch_(opts.batch_records) {
  refuseBinaryForms();
  {
    struct stat st {};
    if (::fstat(in_.fd(), &st) == 0) size_at_open_ = static_cast<uint64_t>(st.st_size);
  }
  // Comment header (its metadata lines go to parseMetadata), up to the column line.
  if (!nextContentLine())  // lines are 1-based: an empty file's error is on line 1
    throw TraceError::inCsv(path_, std::max<uint64_t>(in_.number(), 1), in_.nextOffset(), std::nullopt, "header",
                            fmt::format("no column line '{}' (empty file or only comments)", kCsvColumnLine));
  if (const std::string_view line = in_.line(); line != kCsvColumnLine)
    fail(in_.offset(), std::nullopt, "header",
         fmt::format("expected the column line '{}', found '{}'", kCsvColumnLine, line.substr(0, 80)));
  data_offset_ = in_.nextOffset();
  data_line_ = in_.number() + 1;

  // Frame size: the comment header wins, else the caller's options.
  header_.width = meta_width_.value_or(opts.width);
  header_.height = meta_height_.value_or(opts.height);
  for (const auto& [name, v] : {std::pair{"width", header_.width}, {"height", header_.height}}) {
    if (v == 0)
      fail(in_.offset(), std::nullopt, name,
           "no frame size: the CSV has no '# width' / '# height' comment lines; pass --width and "
           "--height");
    if (v > fv::kMaxFrameSize)
      fail(in_.offset(), std::nullopt, name,
           fmt::format("{} {} exceeds {} (x and y are u16)", name, v, fv::kMaxFrameSize));
  }
  rules_.width = header_.width;
  rules_.height = header_.height;
  if (header_.version == fv::kVersion2)
    for (const DrawInfo& d : header_.draws)
      if (!d.state)
        fail(in_.offset(), std::nullopt, "draw-state",
             fmt::format("version 2: draw {} has no '# draw-state' line", d.id));

  // Pass 1: validate every row, count them, complete the draw table.
  uint64_t count = 0;
  while (nextContentLine()) parseRow(count++, true);
  header_.fragment_count = count;
  rules_.draws = DrawSet(header_.draws);
  buf_.resize(static_cast<size_t>(std::min<uint64_t>(batch_, count)));
  rewind();
}

void CsvReader::refuseBinaryForms() {
  const std::string_view have = in_.peek(sizeof fv::kMagic);
  auto hex = [&] {
    std::string h;
    for (const char c : have) h += fmt::format("{}{:02X}", h.empty() ? "" : " ", static_cast<unsigned char>(c));
    return h;
  };
  if (have.size() >= 5 && std::memcmp(have.data(), fv::kMagic, 5) == 0)
    throw TraceError::inCsv(path_, 1, 0, std::nullopt, "header",
                            fmt::format("found {}, the magic of a binary trace: this looks like a binary .oitt trace "
                                        "(the .csv extension makes it read as CSV; rename it or convert it)",
                                        hex()));
  if (have.size() >= 2 && static_cast<unsigned char>(have[0]) == 0x1F && static_cast<unsigned char>(have[1]) == 0x8B)
    throw TraceError::inCsv(path_, 1, 0, std::nullopt, "header",
                            fmt::format("found {}: the file is gzip-compressed: decompress first (gunzip)", hex()));
}

bool CsvReader::nextContentLine() {
  while (in_.next()) {
    const std::string_view line = in_.line();
    if (allBlank(line)) continue;
    if (line.front() == '#') {
      // Metadata: read in the header; after the column line, where it would be
      // silently ignored, parseMetadata refuses it.
      parseMetadata(line);
      continue;
    }
    return true;
  }
  return false;
}

template <class T>
bool parseNumber(std::string_view s, T& out) {
  if (s.empty()) return false;
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size();
}

void CsvReader::parseMetadata(std::string_view line) {
  CsvTokens t(line.substr(1), in_.offset() + 1);
  const std::string key(t.next());
  auto err = [&](const std::string& msg) { fail(t.offset(), std::nullopt, key, msg); };
  auto expectEnd = [&] {
    if (const std::string_view extra = t.next(); !extra.empty())
      err(fmt::format("unexpected '{}' at the end of the '# {}' line", extra, key));
  };
  const bool after_columns = data_offset_ != 0;
  const bool known = key == "oitsim-trace" || key == "width" || key == "height" ||
                     key == "camera" || key == "encoding" || key == "draw" || key == "draw-state";
  if (!known) return;  // a free comment
  if (after_columns)
    err(fmt::format("'# {}' metadata must come before the column line '{}'", key, kCsvColumnLine));

  if (key == "oitsim-trace") {
    const std::string_view v = t.next();
    if (meta_version_) err("duplicate '# oitsim-trace' line");
    if (v != "v1" && v != "v2")
      err(fmt::format("unsupported version '{}': this build reads v1 and v2", v));
    header_.version = v == "v2" ? fv::kVersion2 : fv::kVersion;
    meta_version_ = true;
    expectEnd();
  } else if (key == "width" || key == "height") {
    std::optional<uint32_t>& slot = key == "width" ? meta_width_ : meta_height_;
    if (slot) err(fmt::format("duplicate '# {}' line", key));
    const std::string_view v = t.next();
    uint32_t n = 0;
    if (!parseNumber(v, n) || n == 0 || n > fv::kMaxFrameSize)
      err(fmt::format("{} '{}': expected an integer in 1..{}", key, v, fv::kMaxFrameSize));
    slot = n;
    expectEnd();
  } else if (key == "camera") {
    if (meta_camera_) err("duplicate '# camera' line");
    float planes[2];
    for (float& p : planes) {
      const std::string_view v = t.next();
      if (!parseNumber(v, p)) err(fmt::format("camera plane '{}' is not a number", v));
    }
    if (auto p = cameraProblem(planes[0], planes[1])) err(*p);
    header_.camera = CameraPlanes{planes[0], planes[1]};
    meta_camera_ = true;
    expectEnd();
  } else if (key == "encoding") {
    if (meta_encoding_) err("duplicate '# encoding' line");
    const std::string_view v = t.next();
    if (v == "fp32")
      header_.encoding = ColourEncoding::Fp32;
    else if (v == "unorm8")
      header_.encoding = ColourEncoding::Unorm8;
    else
      err(fmt::format("bad encoding '{}': expected fp32 or unorm8", v));
    meta_encoding_ = true;
    expectEnd();
  } else if (key == "draw-state") {  // format v2: after the draw's own line
    if (header_.version != fv::kVersion2) err("'# draw-state' lines need '# oitsim-trace v2' first");
    uint32_t id = 0;
    const std::string_view v = t.next();
    auto it = parseNumber(v, id) ? draws_.find(id) : draws_.end();
    if (it == draws_.end()) err(fmt::format("'{}' is not the id of a draw declared above", v));
    DrawInfo& d = header_.draws[it->second.index];
    if (d.state) err(fmt::format("duplicate '# draw-state' line for draw {}", id));
    oit::DrawState s;
    if (auto p = parseDrawStateCsv(t.rest(), s)) err(*p);
    d.state = s;
    if (auto p = drawStateProblem(d, it->second.index)) err(p->message);
  } else {  // draw ID CLASS "NAME"
    DrawInfo d;
    const std::string_view id = t.next();
    if (!parseNumber(id, d.id)) err(fmt::format("draw id '{}' is not a u32", id));
    const uint64_t id_offset = t.offset();
    const std::string_view cls = t.next();
    if (cls == "opaque")
      d.cls = DrawClass::Opaque;
    else if (cls == "transparent")
      d.cls = DrawClass::Transparent;
    else
      err(fmt::format("bad draw class '{}': expected opaque or transparent", cls));
    const std::string_view rest = t.rest();
    size_t i = 1;
    bool closed = false;
    if (rest.empty() || rest[0] != '"') err("expected the draw name in double quotes");
    for (; i < rest.size(); ++i) {
      if (rest[i] == '"') {
        closed = true;
        ++i;
        break;
      }
      if (rest[i] == '\\') {
        if (i + 1 >= rest.size() || (rest[i + 1] != '"' && rest[i + 1] != '\\'))
          err("bad escape in the draw name: only \\\" and \\\\ are allowed");
        ++i;
      }
      d.name += rest[i];
    }
    if (!closed) err("the draw name has no closing double quote");
    if (!allBlank(rest.substr(i))) err("unexpected text after the draw name");
    if (auto p = drawNameProblem(d.name)) err(*p);
    if (auto it = draws_.find(d.id); it != draws_.end())
      fail(id_offset, std::nullopt, key,
           fmt::format("duplicate draw id {} (also declared at line {})", d.id, it->second.where_line));
    if (header_.draws.size() >= fv::kMaxDraws)
      fail(id_offset, std::nullopt, key, tooManyDraws(d.id));
    draws_.emplace(d.id, CsvDraw{header_.draws.size(), true, in_.number()});
    header_.draws.push_back(std::move(d));
  }
}

Fragment CsvReader::parseRow(uint64_t record, bool first_pass) {
  const std::string_view line = in_.line();
  const uint64_t base = in_.offset();
  auto err = [&](size_t col, size_t at, const std::string& msg) {
    fail(base + at, record, kColumnNames[col], msg);
  };
  // Split into exactly 10 fields, remembering where each starts.
  std::string_view field[kColumns];
  size_t start[kColumns];
  size_t p = 0;
  for (size_t c = 0; c < kColumns; ++c) {
    const size_t comma = line.find(',', p);
    const bool last = c + 1 == kColumns;
    if (!last && comma == std::string_view::npos)
      err(c + 1, line.size(), fmt::format("row has {} columns, expected {} ({})", c + 1, kColumns,
                                          kCsvColumnLine));
    if (last && comma != std::string_view::npos)
      err(c, comma, fmt::format("row has more than {} columns, expected {} ({})", kColumns,
                                kColumns, kCsvColumnLine));
    const size_t end = last ? line.size() : comma;
    std::string_view raw = line.substr(p, end - p);
    size_t lead = 0;
    while (lead < raw.size() && isCsvBlank(raw[lead])) ++lead;
    start[c] = p + lead;
    field[c] = trim(raw);
    if (field[c].empty()) err(c, start[c], "empty field");
    p = end + 1;
  }
  auto u64 = [&](size_t c, uint64_t max) {
    uint64_t v = 0;
    if (!parseNumber(field[c], v))
      err(c, start[c], fmt::format("'{}' is not an unsigned decimal integer", field[c]));
    if (v > max) err(c, start[c], fmt::format("{} is out of range (at most {})", v, max));
    return v;
  };
  auto unit = [&](size_t c, fv::Field f) {
    float v = 0;
    const std::string_view s = field[c];
    const auto [q, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (q != s.data() + s.size() || (ec != std::errc() && ec != std::errc::result_out_of_range))
      err(c, start[c], fmt::format("'{}' is not a decimal number", s));
    if (ec == std::errc::result_out_of_range)
      err(c, start[c], fmt::format("'{}' is not representable as fp32", s));
    if (auto msg = unitMessage(f, v)) err(c, start[c], *msg);
    return v;
  };

  Fragment f{};
  f.draw = static_cast<uint32_t>(u64(kDraw, UINT32_MAX));
  f.prim = static_cast<uint32_t>(u64(kPrim, UINT32_MAX));
  const uint64_t x = u64(kX, UINT64_MAX), y = u64(kY, UINT64_MAX);
  if (x >= rules_.width) err(kX, start[kX], coordMessage(fv::Field::X, x, rules_.width));
  if (y >= rules_.height) err(kY, start[kY], coordMessage(fv::Field::Y, y, rules_.height));
  f.x = static_cast<uint16_t>(x);
  f.y = static_cast<uint16_t>(y);
  f.z = unit(kZ, fv::Field::Z);
  f.r = unit(kR, fv::Field::R);
  f.g = unit(kG, fv::Field::G);
  f.b = unit(kB, fv::Field::B);
  f.a = unit(kA, fv::Field::A);
  if (field[kOpaque] != "0" && field[kOpaque] != "1")
    err(kOpaque, start[kOpaque], fmt::format("'{}': expected 0 or 1", field[kOpaque]));
  const DrawClass cls = field[kOpaque] == "1" ? DrawClass::Opaque : DrawClass::Transparent;

  auto it = draws_.find(f.draw);
  if (it == draws_.end()) {
    if (!first_pass)
      throw TraceError::inCsv(path_, in_.number(), base, record, "draw",
                              fmt::format("the trace changed while it was read: draw {} was not in the file when "
                                          "it was opened (a trace must not change during a run)",
                                          f.draw));
    // The table's limit is checked here, at the row that would break it (the
    // binary writer would only find out after the whole first pass).
    if (header_.draws.size() >= fv::kMaxDraws) err(kDraw, start[kDraw], tooManyDraws(f.draw));
    if (header_.version == fv::kVersion2)
      err(kDraw, start[kDraw], fmt::format("draw {} is not declared: version 2 declares every draw with its state", f.draw));
    // Undeclared draw: named after its id, classed by its opaque column.
    draws_.emplace(f.draw, CsvDraw{header_.draws.size(), false, in_.number()});
    header_.draws.push_back(DrawInfo{f.draw, cls, fmt::format("draw{}", f.draw)});
  } else if (header_.draws[it->second.index].cls != cls) {
    const CsvDraw& s = it->second;
    err(kOpaque, start[kOpaque],
        fmt::format("opaque {} but draw {} is {} ({} line {})", field[kOpaque], f.draw,
                    toString(header_.draws[s.index].cls),
                    s.declared ? "declared by the comment header at" : "its first row is at",
                    s.where_line));
  }
  if (header_.encoding == ColourEncoding::Unorm8) {
    // What the binary form of this trace would hold.
    f.r = quantizeUnorm8(f.r);
    f.g = quantizeUnorm8(f.g);
    f.b = quantizeUnorm8(f.b);
    f.a = quantizeUnorm8(f.a);
  }
  return f;
}

std::span<const Fragment> CsvReader::next() {
  // The read buffer may hold the rest of a small file: the size tells a
  // shortened file even then (also at the end, so no run ends on one).
  struct stat st {};
  if (::fstat(in_.fd(), &st) == 0 && static_cast<uint64_t>(st.st_size) < size_at_open_)
    throw TraceError::inCsv(path_, in_.number(), in_.nextOffset(), pos_, "",
                            fmt::format("the trace changed while it was read: it is now {} bytes, it was {} bytes "
                                        "when opened (a trace must not change during a run)",
                                        st.st_size, size_at_open_));
  size_t n = 0;
  while (n < buf_.size() && pos_ + n < header_.fragment_count) {
    if (!nextContentLine())
      throw TraceError::inCsv(path_, in_.number(), in_.nextOffset(), pos_ + n, "",
                              fmt::format("the trace changed while it was read: it now ends before record {} "
                                          "of {} (a trace must not change during a run)",
                                          pos_ + n, header_.fragment_count));
    buf_[n] = parseRow(pos_ + n, false);
    ++n;
  }
  pos_ += n;
  return {buf_.data(), n};
}

}  // namespace

std::unique_ptr<FragmentSource> openCsvTrace(const std::string& path, const OpenOptions& opts) {
  return std::make_unique<CsvReader>(path, opts);
}

}  // namespace oit::detail
