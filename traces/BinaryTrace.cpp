// Binary trace format v1 (FORMAT.md): mmap-based validating reader and
// buffered writer. The reader copies each batch out of the mapping (through
// copyFromMapping, so a trace truncated under a run is an error, not a
// SIGBUS) and validates the copy.
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <unordered_map>

#include "traces/AtomicFile.hpp"
#include "traces/InputFile.hpp"
#include "traces/MappedCopy.hpp"
#include "traces/TraceBackends.hpp"
#include "traces/TraceFormat.hpp"
#include "traces/DrawStateTable.hpp"
#include "traces/TraceRules.hpp"

namespace oit::detail {

namespace fv = format_v1;

namespace {

template <class T>
T load(const unsigned char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

template <class T>
void store(unsigned char* p, T v) {
  std::memcpy(p, &v, sizeof v);
}

std::string hexBytes(const unsigned char* p, size_t n) {
  std::string s;
  for (size_t i = 0; i < n; ++i) s += fmt::format("{}{:02X}", i ? " " : "", p[i]);
  return s;
}

std::string changedMessage(const std::string& what);

class BinaryReader final : public FragmentSource {
 public:
  BinaryReader(const std::string& path, const OpenOptions& opts);

  const TraceHeader& header() const override { return header_; }
  const std::string& path() const override { return path_; }
  uint64_t position() const override { return pos_; }
  void rewind() override {
    pos_ = 0;
    released_ = 0;  // pages we dropped are faulted in again from the page cache
  }
  std::span<const Fragment> next() override;

 private:
  [[noreturn]] void fail(uint64_t offset, std::optional<uint64_t> record, std::string field,
                         const std::string& msg) const {
    throw TraceError(path_, offset, record, std::move(field), msg);
  }
  void parseHeader();
  void releaseBelow(uint64_t offset);
  // Throws "the trace changed while it was read" unless the file still has the
  // size it had at open (a file shrunk inside its last page gives zeros, not a
  // SIGBUS, so the size is checked for every batch and at the end).
  void checkUnchanged(uint64_t record) const;
  [[noreturn]] void changed(uint64_t record, const std::string& what) const;

  // Owns the mapping, so it is unmapped even when the constructor throws.
  struct Mapping {
    void* p = nullptr;
    size_t n = 0;
    Mapping() = default;
    Mapping(const Mapping&) = delete;
    Mapping& operator=(const Mapping&) = delete;
    ~Mapping() {
      if (p) ::munmap(p, n);
    }
  };

  std::string path_;
  TraceHeader header_;
  FileDescriptor fd_;  // kept open for the size checks
  Mapping mapping_;
  unsigned char* map_ = nullptr;  // mapping_.p
  uint64_t size_ = 0;
  uint64_t data_offset_ = 0;  // header_bytes
  uint32_t record_bytes_ = 0;
  uint64_t pos_ = 0;
  size_t batch_ = 0;
  uint64_t released_ = 0;  // [0, released_) of the mapping has been given back
  uint64_t page_ = 4096;
  RecordRules rules_;
  std::vector<Fragment> batch_buf_;        // one batch, copied out of the mapping (fp32) or decoded (unorm8)
  std::vector<unsigned char> raw_;         // unorm8 only: one batch of raw records
};

BinaryReader::BinaryReader(const std::string& path, const OpenOptions& opts)
    : path_(path), batch_(opts.batch_records) {
  // Non-blocking open of a regular file only: a FIFO or a device is refused
  // before anything is read (the reader maps the whole file).
  InputFile in = openInputFile(path);
  if (!in) throw TraceError(path_, in.problem);
  fd_ = std::move(in.fd);
  size_ = in.size;
  if (size_ > 0) {
    void* m = ::mmap(nullptr, size_, PROT_READ, MAP_SHARED, fd_.get(), 0);
    if (m == MAP_FAILED) throw TraceError(path_, fmt::format("cannot mmap: {}", std::strerror(errno)));
    mapping_.p = m;
    mapping_.n = size_;
    map_ = static_cast<unsigned char*>(m);
  }
  page_ = static_cast<uint64_t>(::sysconf(_SC_PAGESIZE));
  parseHeader();
  if (map_) ::madvise(map_, size_, MADV_SEQUENTIAL);
}

void BinaryReader::parseHeader() {
  // The header is parsed from copies (a file truncated since the fstat() would
  // fault in the mapping): first the fixed header, then the draw table.
  unsigned char fixed[fv::kFixedHeaderBytes] = {};
  const size_t fixed_have = static_cast<size_t>(std::min<uint64_t>(size_, fv::kFixedHeaderBytes));
  if (fixed_have > 0 && !copyFromMapping(fixed, map_, fixed_have))
    throw TraceError(path_, changedMessage("its header cannot be read any more"));
  // Magic first: a CSV or foreign file must say so, not "truncated".
  const size_t magic_have = static_cast<size_t>(std::min<uint64_t>(size_, sizeof fv::kMagic));
  if (std::memcmp(fixed, fv::kMagic, magic_have) != 0) {
    std::string hint = ": not an oitsim binary trace";
    const std::string_view start(reinterpret_cast<const char*>(fixed), magic_have);
    if (start.starts_with("# oitsim") || start.starts_with("draw,pri"))
      hint = ": this looks like a CSV trace; CSV traces need a .csv extension";
    fail(0, std::nullopt, "magic",
         fmt::format("bad magic: expected {}, found {}{}", hexBytes(fv::kMagic, 8),
                     hexBytes(fixed, magic_have), hint));
  }
  if (size_ < fv::kFixedHeaderBytes)
    fail(size_, std::nullopt, "header",
         fmt::format("truncated header: the file ends at byte offset {}, the fixed header needs {} "
                     "bytes",
                     size_, fv::kFixedHeaderBytes));
  const unsigned char* h = fixed;
  header_.version = load<uint32_t>(h + fv::kOffVersion);
  if (header_.version != fv::kVersion && header_.version != fv::kVersion2)
    fail(fv::kOffVersion, std::nullopt, "version",
         fmt::format("unsupported version {}: this build reads versions 1 and 2", header_.version));
  const uint32_t header_bytes = load<uint32_t>(h + fv::kOffHeaderBytes);
  header_.width = load<uint32_t>(h + fv::kOffWidth);
  header_.height = load<uint32_t>(h + fv::kOffHeight);
  const std::pair<const char*, uint32_t> sizes[] = {{"width", header_.width},
                                                    {"height", header_.height}};
  for (size_t i = 0; i < 2; ++i) {
    const auto [name, v] = sizes[i];
    const size_t off = i == 0 ? fv::kOffWidth : fv::kOffHeight;
    if (v == 0)
      fail(off, std::nullopt, name, fmt::format("{} is 0, expected 1..{}", name, fv::kMaxFrameSize));
    if (v > fv::kMaxFrameSize)
      fail(off, std::nullopt, name,
           fmt::format("{} {} exceeds {} (x and y are u16)", name, v, fv::kMaxFrameSize));
  }
  const uint64_t count = load<uint64_t>(h + fv::kOffFragmentCount);
  const uint32_t enc = load<uint32_t>(h + fv::kOffEncoding);
  header_.encoding = static_cast<ColourEncoding>(enc);
  record_bytes_ = fv::recordBytes(header_.encoding);
  if (record_bytes_ == 0)
    fail(fv::kOffEncoding, std::nullopt, "encoding",
         fmt::format("bad encoding {}: expected 0 (fp32) or 1 (unorm8)", enc));
  const uint32_t rb = load<uint32_t>(h + fv::kOffRecordBytes);
  if (rb != record_bytes_)
    fail(fv::kOffRecordBytes, std::nullopt, "record_bytes",
         fmt::format("record_bytes {} does not match encoding {} (expected {})", rb,
                     toString(header_.encoding), record_bytes_));
  const uint32_t flags = load<uint32_t>(h + fv::kOffFlags);
  if (flags & ~fv::kKnownFlags)
    fail(fv::kOffFlags, std::nullopt, "flags",
         fmt::format("unknown flag bits 0x{:08X}: version 1 defines only bit 0 (camera)",
                     flags & ~fv::kKnownFlags));
  const float near_plane = load<float>(h + fv::kOffCameraNear);
  const float far_plane = load<float>(h + fv::kOffCameraFar);
  if (flags & fv::kFlagCamera) {
    if (auto p = cameraProblem(near_plane, far_plane)) fail(fv::kOffCameraNear, std::nullopt, "camera", *p);
    header_.camera = CameraPlanes{near_plane, far_plane};
  } else if (load<uint32_t>(h + fv::kOffCameraNear) != 0 || load<uint32_t>(h + fv::kOffCameraFar) != 0) {
    fail(fv::kOffCameraNear, std::nullopt, "camera",
         "camera planes set but the camera flag (bit 0 of flags) is clear: expected zero bytes");
  }
  for (size_t i = 0; i < fv::kReservedBytes; ++i)
    if (h[fv::kOffReserved + i] != 0)
      fail(fv::kOffReserved + i, std::nullopt, "reserved",
           fmt::format("reserved byte is 0x{:02X}, expected 0", h[fv::kOffReserved + i]));
  const uint32_t draw_count = load<uint32_t>(h + fv::kOffDrawCount);
  if (draw_count > fv::kMaxDraws)
    fail(fv::kOffDrawCount, std::nullopt, "draw_count",
         fmt::format("draw_count {} exceeds the limit {}", draw_count, fv::kMaxDraws));
  const uint64_t min_header = fv::headerBytesFor(draw_count, header_.version);
  if (header_bytes % 64 != 0 || header_bytes < min_header)
    fail(fv::kOffHeaderBytes, std::nullopt, "header_bytes",
         fmt::format("header_bytes {}: expected a multiple of 64 and at least {} (64 + 64 x {} "
                     "draws{})",
                     header_bytes, min_header, draw_count,
                     header_.version == fv::kVersion2 ? " + 32 x draws of draw state, rounded up to 64" : ""));
  if (size_ < header_bytes) {
    std::string where = size_ < min_header
                            ? fmt::format("inside draw table entry {}",
                                          (size_ - fv::kFixedHeaderBytes) / fv::kDrawEntryBytes)
                            : std::string("before the end of the header");
    fail(size_, std::nullopt, "header",
         fmt::format("truncated header: the file ends at byte offset {}, {}; header_bytes is {}",
                     size_, where, header_bytes));
  }

  // Draw table (and, in version 2, the draw state table after it).
  std::vector<unsigned char> table(static_cast<size_t>(min_header - fv::kFixedHeaderBytes));
  if (!table.empty() && !copyFromMapping(table.data(), map_ + fv::kFixedHeaderBytes, table.size()))
    throw TraceError(path_, changedMessage("its draw table cannot be read any more"));
  std::unordered_map<uint32_t, uint32_t> seen;
  header_.draws.reserve(draw_count);
  for (uint32_t i = 0; i < draw_count; ++i) {
    const uint64_t entry = fv::kFixedHeaderBytes + uint64_t{i} * fv::kDrawEntryBytes;
    const unsigned char* e = table.data() + (entry - fv::kFixedHeaderBytes);
    DrawInfo d;
    d.id = load<uint32_t>(e + fv::kDrawOffId);
    if (auto [it, fresh] = seen.emplace(d.id, i); !fresh)
      fail(entry + fv::kDrawOffId, std::nullopt, fmt::format("draw[{}].id", i),
           fmt::format("duplicate draw id {} (also draw table entry {} at byte offset {})", d.id,
                       it->second, fv::kFixedHeaderBytes + uint64_t{it->second} * fv::kDrawEntryBytes));
    const uint32_t cls = load<uint32_t>(e + fv::kDrawOffClass);
    if (cls > 1)
      fail(entry + fv::kDrawOffClass, std::nullopt, fmt::format("draw[{}].class", i),
           fmt::format("bad draw class {}: expected 0 (opaque) or 1 (transparent)", cls));
    d.cls = static_cast<DrawClass>(cls);
    const auto* name = reinterpret_cast<const char*>(e + fv::kDrawOffName);
    const size_t len = ::strnlen(name, fv::kDrawNameField);
    if (len == fv::kDrawNameField)
      fail(entry + fv::kDrawOffName, std::nullopt, fmt::format("draw[{}].name", i),
           fmt::format("name is not NUL-terminated within its {} bytes", fv::kDrawNameField));
    for (size_t k = len; k < fv::kDrawNameField; ++k)
      if (name[k] != 0)
        fail(entry + fv::kDrawOffName + k, std::nullopt, fmt::format("draw[{}].name", i),
             "non-zero byte after the name's terminating NUL: expected NUL padding");
    d.name.assign(name, len);
    if (auto p = drawNameProblem(d.name))
      fail(entry + fv::kDrawOffName, std::nullopt, fmt::format("draw[{}].name", i), *p);
    header_.draws.push_back(std::move(d));
  }
  if (header_.version == fv::kVersion2)
    if (auto p = readDrawStates(table.data() + (fv::drawStateTableOffset(draw_count) - fv::kFixedHeaderBytes),
                                header_.draws))
      fail(p->offset, std::nullopt, p->field, p->message);

  // Record count against the file size: catches truncation at open.
  if (count == fv::kUnfinishedCount)
    fail(fv::kOffFragmentCount, std::nullopt, "fragment_count",
         "fragment_count is the unfinished-writer sentinel 0xFFFFFFFFFFFFFFFF: the writer never "
         "committed (it crashed or was interrupted), so the trace is incomplete");
  const uint64_t data = size_ - header_bytes;
  const bool fits = count <= (UINT64_MAX - header_bytes) / record_bytes_;
  const uint64_t expected = fits ? count * record_bytes_ : UINT64_MAX;
  if (data < expected) {
    const uint64_t rec = data / record_bytes_;
    fail(size_, rec, "",
         fmt::format("truncated: the file ends at byte offset {}, inside record {} (which starts at "
                     "byte offset {}); the header declares {} records of {} bytes{}",
                     size_, rec, header_bytes + rec * record_bytes_, count, record_bytes_,
                     fits ? fmt::format(", so the file should be {} bytes", header_bytes + expected)
                          : std::string()));
  }
  if (data > expected) {
    const uint64_t extra = data - expected;
    fail(header_bytes + expected, count, "fragment_count",
         fmt::format("count mismatch: the header declares {} records but {} more bytes follow the "
                     "last one{} (the file is {} bytes, expected {})",
                     count, extra,
                     extra % record_bytes_ == 0
                         ? fmt::format(", {} whole records", extra / record_bytes_)
                         : std::string(),
                     size_, header_bytes + expected));
  }
  header_.fragment_count = count;
  data_offset_ = header_bytes;
  rules_.width = header_.width;
  rules_.height = header_.height;
  rules_.draws = DrawSet(header_.draws);
  batch_buf_.resize(static_cast<size_t>(std::min<uint64_t>(batch_, count)));
  if (header_.encoding == ColourEncoding::Unorm8) raw_.resize(batch_buf_.size() * record_bytes_);
}

std::string changedMessage(const std::string& what) {
  return fmt::format("the trace changed while it was read: {} (another process truncated or rewrote it; a trace "
                     "must not change during a run)",
                     what);
}

void BinaryReader::changed(uint64_t record, const std::string& what) const {
  throw TraceError(path_, data_offset_ + record * record_bytes_, record, "", changedMessage(what));
}

void BinaryReader::checkUnchanged(uint64_t record) const {
  struct stat st {};
  if (::fstat(fd_.get(), &st) != 0) changed(record, fmt::format("cannot stat it: {}", std::strerror(errno)));
  if (static_cast<uint64_t>(st.st_size) < size_)
    changed(record, fmt::format("it is now {} bytes, it was {} bytes when opened", st.st_size, size_));
}

void BinaryReader::releaseBelow(uint64_t offset) {
  const uint64_t aligned = offset & ~(page_ - 1);
  if (aligned > released_) {
    // Consumed pages stay in the page cache but leave our resident set.
    ::madvise(map_ + released_, aligned - released_, MADV_DONTNEED);
    released_ = aligned;
  }
}

std::span<const Fragment> BinaryReader::next() {
  const uint64_t count = header_.fragment_count;
  if (pos_ >= count) {
    checkUnchanged(pos_);  // a run ends only on records that were all there
    return {};
  }
  const size_t n = static_cast<size_t>(std::min<uint64_t>(batch_, count - pos_));
  const uint64_t begin = data_offset_ + pos_ * record_bytes_;
  // The previous batch's copy is dead now: its pages can go.
  releaseBelow(begin);
  checkUnchanged(pos_);
  Fragment* out = batch_buf_.data();
  size_t bad = n;
  if (header_.encoding == ColourEncoding::Fp32) {
    // fp32 records are exactly oit::Fragment: copy, then validate the copy.
    if (!copyFromMapping(out, map_ + begin, n * sizeof(Fragment)))
      changed(pos_, fmt::format("its records from byte offset {} on are gone", begin));
    bad = firstInvalid({out, n}, rules_);
  } else {
    if (!copyFromMapping(raw_.data(), map_ + begin, n * record_bytes_))
      changed(pos_, fmt::format("its records from byte offset {} on are gone", begin));
    bad = decodeUnorm8(raw_.data(), out, n, rules_);
  }
  if (bad < n) {
    const Violation v = *checkRecord(out[bad], rules_);
    const uint64_t rec = pos_ + bad;
    fail(data_offset_ + rec * record_bytes_ + fv::fieldOffset(header_.encoding, v.field), rec,
         fv::fieldName(v.field), v.message);
  }
  pos_ += n;
  return {out, n};
}

class BinaryWriter final : public FragmentSink {
 public:
  BinaryWriter(const std::string& path, const TraceHeader& header);
  void write(const Fragment& f) override { write(std::span<const Fragment>(&f, 1)); }
  void write(std::span<const Fragment> fs) override;
  void commit() override;
  uint64_t written() const override { return written_; }

 private:
  void append(std::span<const Fragment> fs);

  TraceHeader header_;
  RecordRules rules_;
  uint32_t record_bytes_;
  uint64_t data_offset_;
  AtomicFile file_;
  uint64_t written_ = 0;
};

BinaryWriter::BinaryWriter(const std::string& path, const TraceHeader& header)
    : header_(checkHeaderForWrite(path, header)),
      record_bytes_(fv::recordBytes(header.encoding)),
      data_offset_(fv::headerBytesFor(header.draws.size(), header.version)),
      file_(path) {
  rules_.width = header_.width;
  rules_.height = header_.height;
  rules_.draws = DrawSet(header_.draws);
  std::vector<unsigned char> h(data_offset_, 0);
  std::memcpy(h.data() + fv::kOffMagic, fv::kMagic, sizeof fv::kMagic);
  store<uint32_t>(&h[fv::kOffVersion], header_.version);
  store<uint32_t>(&h[fv::kOffHeaderBytes], static_cast<uint32_t>(data_offset_));
  store<uint32_t>(&h[fv::kOffWidth], header_.width);
  store<uint32_t>(&h[fv::kOffHeight], header_.height);
  store<uint64_t>(&h[fv::kOffFragmentCount], fv::kUnfinishedCount);
  store<uint32_t>(&h[fv::kOffEncoding], static_cast<uint32_t>(header_.encoding));
  store<uint32_t>(&h[fv::kOffRecordBytes], record_bytes_);
  if (header_.camera) {
    store<uint32_t>(&h[fv::kOffFlags], fv::kFlagCamera);
    store<float>(&h[fv::kOffCameraNear], header_.camera->near_plane);
    store<float>(&h[fv::kOffCameraFar], header_.camera->far_plane);
  }
  store<uint32_t>(&h[fv::kOffDrawCount], static_cast<uint32_t>(header_.draws.size()));
  for (size_t i = 0; i < header_.draws.size(); ++i) {
    unsigned char* e = &h[fv::kFixedHeaderBytes + i * fv::kDrawEntryBytes];
    const DrawInfo& d = header_.draws[i];
    store<uint32_t>(e + fv::kDrawOffId, d.id);
    store<uint32_t>(e + fv::kDrawOffClass, static_cast<uint32_t>(d.cls));
    std::memcpy(e + fv::kDrawOffName, d.name.data(), d.name.size());
  }
  if (header_.version == fv::kVersion2)
    writeDrawStates(&h[fv::drawStateTableOffset(header_.draws.size())], header_.draws);
  file_.append(h.data(), h.size());
}

void BinaryWriter::write(std::span<const Fragment> fs) {
  if (file_.committed()) throw std::logic_error("FragmentSink::write after commit()");
  const size_t bad = firstInvalid(fs, rules_);
  append(fs.first(bad));  // like writing one by one: records before the bad one are kept
  written_ += bad;
  if (bad < fs.size()) {
    const Violation v = *checkRecord(fs[bad], rules_);
    throw TraceError(file_.path(),
                     data_offset_ + written_ * record_bytes_ + fv::fieldOffset(header_.encoding, v.field),
                     written_, fv::fieldName(v.field), v.message);
  }
}

void BinaryWriter::append(std::span<const Fragment> fs) {
  if (header_.encoding == ColourEncoding::Fp32) {
    file_.append(fs.data(), fs.size_bytes());
    return;
  }
  for (const Fragment& f : fs) {
    unsigned char* p = file_.space(fv::kUnorm8RecordBytes);
    std::memcpy(p + 0, &f.x, 2);
    std::memcpy(p + 2, &f.y, 2);
    std::memcpy(p + 4, &f.z, 4);
    p[8] = encodeUnorm8(f.r);
    p[9] = encodeUnorm8(f.g);
    p[10] = encodeUnorm8(f.b);
    p[11] = encodeUnorm8(f.a);
    std::memcpy(p + 12, &f.prim, 4);
    std::memcpy(p + 16, &f.draw, 4);
    file_.advance(fv::kUnorm8RecordBytes);
  }
}

void BinaryWriter::commit() {
  if (file_.committed()) return;
  const uint64_t count = written_;
  file_.patch(fv::kOffFragmentCount, &count, sizeof count);
  file_.commit();
}

}  // namespace

std::unique_ptr<FragmentSource> openBinaryTrace(const std::string& path, const OpenOptions& opts) {
  return std::make_unique<BinaryReader>(path, opts);
}

std::unique_ptr<FragmentSink> createBinaryWriter(const std::string& path, const TraceHeader& header) {
  return std::make_unique<BinaryWriter>(path, header);
}

}  // namespace oit::detail
