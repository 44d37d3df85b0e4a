#include "traces/capture/ApitraceStream.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <fstream>
#include <optional>
#include <stdexcept>

#include <fmt/format.h>

#include "traces/capture/ApiOrder.hpp"
#include "traces/capture/interposer/BlendClass.hpp"
#include "traces/capture/interposer/CaptureStream.hpp"

// The stream's blend modes are the trace format's (oit::BlendMode), value for value.
static_assert(uint8_t(oit::BlendMode::Off) == oit::capture::stream::kBlendOff &&
              uint8_t(oit::BlendMode::Over) == oit::capture::stream::kBlendOver &&
              uint8_t(oit::BlendMode::PremultipliedOver) == oit::capture::stream::kBlendPremulOver &&
              uint8_t(oit::BlendMode::Additive) == oit::capture::stream::kBlendAdditive &&
              uint8_t(oit::BlendMode::Multiplicative) == oit::capture::stream::kBlendMultiply &&
              uint8_t(oit::BlendMode::Other) == oit::capture::stream::kBlendOther);

namespace oit::capture {

namespace st = stream;

namespace {

std::string tail(const std::string& text, size_t lines) {
  size_t pos = text.size();
  while (pos > 0 && (text[pos - 1] == '\n')) --pos;
  for (size_t n = 0; n < lines && pos > 0; ++n) {
    pos = text.rfind('\n', pos - 1);
    if (pos == std::string::npos) {
      pos = 0;
      break;
    }
  }
  std::string t = text.substr(pos);
  while (!t.empty() && t.front() == '\n') t.erase(0, 1);
  while (!t.empty() && t.back() == '\n') t.pop_back();
  for (char& c : t)
    if (c == '\n') c = ' ';
  return t;
}

std::string readFile(const std::string& path) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) return {};
  std::string s(static_cast<size_t>(f.tellg()), '\0');
  f.seekg(0);
  f.read(s.data(), static_cast<std::streamsize>(s.size()));
  s.resize(static_cast<size_t>(f.gcount()));
  return s;
}


// Straight RGBA of a record, clamped to what a trace holds; counts what it changed.
void toFragment(const st::GpuRecord& r, const st::DrawChunk& d, FrameCapture& f, Fragment& out) {
  float c[4] = {r.rgba[0], r.rgba[1], r.rgba[2], r.rgba[3]};
  bool clamped = false;
  for (float& v : c) {
    if (!std::isfinite(v)) {
      v = std::isinf(v) && v > 0 ? 1.0f : 0.0f;
      clamped = true;
    } else if (v < 0.0f || v > 1.0f) {
      v = std::clamp(v, 0.0f, 1.0f);
      clamped = true;
    }
  }
  if (d.state.blend_mode == st::kBlendPremulOver) {
    // ONE, ONE_MINUS_SRC_ALPHA blends a premultiplied colour: the trace holds straight colour.
    if (c[3] > 0.0f) {
      for (int k = 0; k < 3; ++k) {
        const float s = c[k] / c[3];
        if (s > 1.0f) ++f.premultiplied_clamped;
        c[k] = std::min(s, 1.0f);
      }
    } else if (c[0] > 0.0f || c[1] > 0.0f || c[2] > 0.0f) {
      c[0] = c[1] = c[2] = 0.0f;
      ++f.premultiplied_zero_alpha;
    }
  }
  if (clamped) ++f.colour_clamped;
  float z = r.z;
  if (!(z >= 0.0f && z <= 1.0f)) {
    z = std::isfinite(z) ? std::clamp(z, 0.0f, 1.0f) : 1.0f;
    ++f.depth_clamped;
  }
  out = Fragment{static_cast<uint16_t>(r.xy & 0xFFFF), static_cast<uint16_t>(r.xy >> 16), z, c[0], c[1], c[2],
                 c[3], r.prim, d.index};
}

DrawState toDrawState(const st::DrawChunk& d, uint64_t fragments) {
  DrawState s;
  s.blend = static_cast<BlendMode>(d.state.blend_mode);
  s.depth_test = d.state.depth_test != 0;
  s.depth_write = d.state.depth_write != 0;
  s.depth_func = d.state.depth_func;
  s.blend_eq_rgb = d.state.blend_eq_rgb;
  s.blend_src_rgb = d.state.blend_src_rgb;
  s.blend_dst_rgb = d.state.blend_dst_rgb;
  s.blend_eq_alpha = d.state.blend_eq_alpha;
  s.blend_src_alpha = d.state.blend_src_alpha;
  s.blend_dst_alpha = d.state.blend_dst_alpha;
  s.fragments = fragments;
  return s;
}

// The full order of two fragments of one draw: API order (primitive, y, x), then
// depth and colour for the equal keys of instanced draws.
bool apiLess(const Fragment& a, const Fragment& b) {
  if (a.prim != b.prim) return a.prim < b.prim;
  if (a.y != b.y) return a.y < b.y;
  if (a.x != b.x) return a.x < b.x;
  if (a.z != b.z) return a.z < b.z;
  if (a.r != b.r) return a.r < b.r;
  if (a.g != b.g) return a.g < b.g;
  if (a.b != b.b) return a.b < b.b;
  return a.a < b.a;
}

// Appends a draw's records to `out` in API order, converted as a trace holds them
// (what conversion changed is counted in `f`).
void appendInApiOrder(const st::DrawChunk& d, const st::GpuRecord* recs, FrameCapture& f, std::vector<Fragment>& out) {
  // Threads append in any order. API order within a draw: primitive, then pixel
  // rows bottom-up, then x (as oitsim gen and the mesh capture emit), by a radix
  // sort of the keys (ApiOrder.hpp); the records are converted in that order.
  const std::vector<uint32_t> order =
      apiOrder(d.records, [&](size_t i) { return RecordKey{recs[i].prim, recs[i].xy}; });
  const size_t first = out.size();
  // The records are read in key order, scattered over the stream: fetch ahead.
  constexpr size_t kAhead = 16;
  for (size_t j = 0; j < order.size(); ++j) {
    if (j + kAhead < order.size()) __builtin_prefetch(&recs[order[j + kAhead]]);
    Fragment frag;
    toFragment(recs[order[j]], d, f, frag);
    out.push_back(frag);
  }
  // Instances and sub-draws restart primitive ids (and a geometry shader may not
  // write one): their fragments at one pixel (equal keys, left in thread order by
  // the stable sort) are ordered by depth and colour, deterministic but not
  // necessarily the instances' order.
  auto run = out.begin() + static_cast<std::ptrdiff_t>(first);
  while (run != out.end()) {
    auto end = run + 1;
    while (end != out.end() && end->prim == run->prim && end->y == run->y && end->x == run->x) ++end;
    if (end - run > 1) std::sort(run, end, apiLess);
    run = end;
  }
}

// Appends one captured draw's records to the frame in API order.
void addDraw(const st::DrawChunk& d, const st::GpuRecord* recs, FrameCapture& f) {
  const auto mode = static_cast<BlendMode>(d.state.blend_mode);
  DrawInfo info;
  info.id = d.index;
  info.cls = mode == BlendMode::Off ? DrawClass::Opaque : DrawClass::Transparent;
  std::string fn(d.function, ::strnlen(d.function, sizeof d.function));
  info.name = fmt::format("{} #{} program {}", fn, d.index, d.program).substr(0, 55);
  info.state = toDrawState(d, d.records);
  f.header.draws.push_back(info);
  if (!d.state.early_tests) ++f.late_depth_draws;
  if (d.instanced) ++f.multi_draws;
  if (d.window) f.window_draws.push_back(d.index);
  if (!info.state->recorded()) return;  // listed, not modelled: its fragments stay out
  appendInApiOrder(d, recs, f, f.fragments);
}

class StreamReader {
 public:
  StreamReader(const char* data, uint64_t size, const std::string& trace) : d_(data), size_(size), trace_(trace) {}
  bool done() const { return pos_ >= size_; }
  template <typename T>
  const T* take(uint64_t n = 1) {
    const uint64_t bytes = sizeof(T) * n;
    if (size_ - pos_ < bytes || bytes / sizeof(T) != n)
      throw std::runtime_error(fmt::format("{}: the interposer's stream ends inside a chunk (the retracer stopped "
                                           "while writing it)", trace_));
    const T* p = reinterpret_cast<const T*>(d_ + pos_);
    pos_ += bytes;
    return p;
  }
  std::string text(uint32_t n) {
    const char* p = take<char>(n);
    return std::string(p, n);
  }

 private:
  const char* d_;
  uint64_t size_;
  const std::string& trace_;
  uint64_t pos_ = 0;
};

// The interposer's stream, mapped read-only: no copy of its records (46 MB for the
// glmark2 frame) into a zero-filled string first.
class MappedStream {
 public:
  // populate: map every page at once (for a full read; a scan of the chunk headers
  // touches few of them).
  MappedStream(const std::string& path, bool populate) {
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return;  // no stream: the caller reports the retracer's failure
    struct stat sb{};
    if (::fstat(fd, &sb) == 0 && sb.st_size > 0) {
      void* p = ::mmap(nullptr, static_cast<size_t>(sb.st_size), PROT_READ,
                       MAP_PRIVATE | (populate ? MAP_POPULATE : 0), fd, 0);
      if (p != MAP_FAILED) {
        data_ = static_cast<const char*>(p);
        size_ = static_cast<uint64_t>(sb.st_size);
      }
    }
    ::close(fd);
  }
  ~MappedStream() {
    if (data_) ::munmap(const_cast<char*>(data_), size_);
  }
  MappedStream(const MappedStream&) = delete;
  MappedStream& operator=(const MappedStream&) = delete;
  const char* data() const { return data_; }
  uint64_t size() const { return size_; }

 private:
  const char* data_ = nullptr;
  uint64_t size_ = 0;
};

// The version of a stream that starts with the interposer's magic (its last
// character), or 0 when it does not.
uint32_t streamVersion(const char* data, uint64_t size) {
  if (size < sizeof st::kMagic || std::memcmp(data, st::kMagic, st::kMagicPrefix) != 0) return 0;
  const char v = data[st::kMagicPrefix];
  return v >= '1' && v <= '9' ? uint32_t(v - '0') : 0;
}

StreamScan scanBytes(const char* data, uint64_t size) {
  StreamScan s;
  uint64_t pos = sizeof(st::StreamHeader);
  // Another version's chunks are not this one's: readStream refuses the stream.
  if (size < pos || streamVersion(data, size) != st::kVersion) return s;
  while (size - pos >= sizeof(st::ChunkHeader)) {
    st::ChunkHeader c;
    std::memcpy(&c, data + pos, sizeof c);
    pos += sizeof c;
    if (c.tag == st::kEnd) {
      st::EndChunk e;
      if (size - pos >= sizeof e) {
        std::memcpy(&e, data + pos, sizeof e);
        s.record_capacity = e.record_capacity;
        s.record_limit = e.record_limit;
      }
      break;
    }
    if (c.tag != st::kDraw && c.tag != st::kCheckDraw) {
      if (c.tag == st::kError) break;
      if (c.tag == st::kVerify) {
        st::FrameChunk f;
        if (size - pos < sizeof f) break;
        std::memcpy(&f, data + pos, sizeof f);
        pos += sizeof f + uint64_t(f.width) * f.height * (4 * sizeof(float) + sizeof(uint32_t));
      } else {
        pos += c.bytes;
      }
      if (pos > size) break;
      continue;
    }
    st::DrawChunk d;
    if (size - pos < sizeof d) break;
    std::memcpy(&d, data + pos, sizeof d);
    pos += sizeof d;
    if (d.records > (size - pos) / sizeof(st::GpuRecord)) break;
    pos += d.records * sizeof(st::GpuRecord);
    if (c.tag == st::kCheckDraw) continue;  // --verify's second drawing of the draw that follows
    if (d.reason == st::kCaptured && d.state.blend_mode <= st::kBlendPremulOver) s.records[d.frame] += d.records;
    if (d.reason == st::kOverflow) s.overflow_need = std::max(s.overflow_need, d.fragments);
  }
  return s;
}

// Room for `n` fragments in one allocation, backed by transparent huge pages where
// the kernel offers them on request (THP "madvise"): a 4 KiB page fault per 128
// fragments was a fifth of oitsim's CPU time on the glmark2 frame.
void reserveFragments(std::vector<Fragment>& v, uint64_t n) {
  v.reserve(n);
  detail::adviseHugePages(v.data(), n * sizeof(Fragment));
}

}  // namespace

StreamScan scanStream(const std::string& stream_path) {
  const MappedStream data(stream_path, false);
  return scanBytes(data.data(), data.size());
}

ApitraceResult readStream(const ApitraceOptions& o, const std::string& retracer, const std::string& interposer,
                          int status, const std::string& stream_path, const std::string& log_path,
                          const StreamScan* scan) {
  ApitraceResult result;
  result.renderer_log = readFile(log_path);
  const MappedStream data(stream_path, true);
  const std::string log_tail = tail(result.renderer_log, 3);
  if (const uint32_t v = streamVersion(data.data(), data.size()); v != 0 && v != st::kVersion)
    throw std::runtime_error(fmt::format("{}: the interposer {} writes capture stream version {}, this oitsim reads "
                                         "version {}: use the interposer built with this oitsim (next to it)",
                                         o.trace, interposer, v, st::kVersion));
  auto retracerFailed = [&](const std::string& what) {
    return std::runtime_error(fmt::format("{}: {} {}{}", o.trace, retracer, what,
                                          log_tail.empty() ? "" : "; its last output: " + log_tail));
  };
  if (data.size() < sizeof(st::StreamHeader) || std::memcmp(data.data(), st::kMagic, sizeof st::kMagic) != 0) {
    if (WIFEXITED(status))
      throw retracerFailed(fmt::format("exited with status {} before the interposer started (is {} the "
                                       "interposer, and the trace an OpenGL trace?)", WEXITSTATUS(status),
                                       interposer));
    throw retracerFailed(fmt::format("was killed by signal {}", WTERMSIG(status)));
  }

  StreamReader in(data.data(), data.size(), o.trace);
  in.take<st::StreamHeader>();
  const StreamScan scanned = scan ? StreamScan{} : scanBytes(data.data(), data.size());
  const std::unordered_map<uint32_t, uint64_t>& frame_records = (scan ? *scan : scanned).records;
  FrameCapture cur;
  std::vector<Fragment> check;  // the check drawing's records of the frame (--verify)
  FrameCapture check_counts;    // what converting them changed (not reported)
  bool have_frame = false;
  std::optional<st::EndChunk> end;
  auto startFrame = [&](uint32_t frame) {
    if (have_frame && cur.frame == frame) return;
    cur = FrameCapture{};
    check.clear();
    cur.frame = frame;
    cur.header.version = 2;
    cur.header.encoding = ColourEncoding::Fp32;
    if (auto it = frame_records.find(frame); it != frame_records.end()) reserveFragments(cur.fragments, it->second);
    have_frame = true;
  };
  while (!in.done() && !end) {
    const st::ChunkHeader c = *in.take<st::ChunkHeader>();
    switch (c.tag) {
      case st::kDraw: {
        const st::DrawChunk d = *in.take<st::DrawChunk>();
        const st::GpuRecord* recs = in.take<st::GpuRecord>(d.records);
        startFrame(d.frame);
        ++cur.draw_calls;
        if (d.reason == st::kCaptured) {
          addDraw(d, recs, cur);
        } else {
          cur.uncaptured.push_back({d.index, d.reason, std::string(d.function, ::strnlen(d.function, sizeof d.function)),
                                    d.program, d.width, d.height, d.fragments});
        }
        break;
      }
      case st::kCheckDraw: {
        const st::DrawChunk d = *in.take<st::DrawChunk>();
        const st::GpuRecord* recs = in.take<st::GpuRecord>(d.records);
        startFrame(d.frame);
        if (d.reason == st::kCaptured) appendInApiOrder(d, recs, check_counts, check);
        break;
      }
      case st::kVerify: {
        const st::FrameChunk f = *in.take<st::FrameChunk>();
        startFrame(f.frame);
        GlTransparentReference ref;
        ref.width = f.width;
        ref.height = f.height;
        const size_t px = size_t(f.width) * f.height;
        const float* rgba = in.take<float>(px * 4);
        const uint32_t* count = in.take<uint32_t>(px);
        ref.rgba.assign(rgba, rgba + px * 4);
        ref.count.assign(count, count + px);
        ref.fragments = std::move(check);
        check.clear();
        cur.reference = std::move(ref);
        break;
      }
      case st::kFrame: {
        const st::FrameChunk f = *in.take<st::FrameChunk>();
        startFrame(f.frame);
        if (f.width == 0 || f.height == 0 || f.width > 65535 || f.height > 65535)
          throw std::runtime_error(fmt::format("{}: frame {}: the application's drawable size {}x{} is unknown or "
                                               "beyond a trace's 65535", o.trace, f.frame, f.width, f.height));
        cur.header.width = f.width;
        cur.header.height = f.height;
        cur.header.fragment_count = cur.fragments.size();
        result.frames.push_back(std::move(cur));
        have_frame = false;
        break;
      }
      case st::kError:
        throw std::runtime_error(fmt::format("{}: {}", o.trace, in.text(c.bytes)));
      case st::kEnd:
        end = *in.take<st::EndChunk>();
        break;
      default:
        throw std::runtime_error(fmt::format("{}: unknown chunk {} in the interposer's stream", o.trace, c.tag));
    }
  }
  if (!end) {
    if (WIFSIGNALED(status)) throw retracerFailed(fmt::format("was killed by signal {}", WTERMSIG(status)));
    throw retracerFailed(fmt::format("stopped without finishing the stream (exit status {})",
                                     WIFEXITED(status) ? WEXITSTATUS(status) : -1));
  }
  if (!end->range_done) {
    const uint32_t frames = end->frames_seen;
    throw std::runtime_error(fmt::format(
        "{}: frame range {}-{} is past the end: the trace has {} frame{} (swap-buffer counts 0-{}){}", o.trace,
        o.first_frame, o.last_frame, frames, frames == 1 ? "" : "s", frames ? frames - 1 : 0,
        frames == 0 ? "; no frame was presented (an EGL trace? the capture replays GLX traces; or the retracer failed: " + log_tail + ")" : ""));
  }
  result.record_capacity = end->record_capacity;
  result.record_limit = end->record_limit;
  static_assert(std::tuple_size_v<decltype(result.deleted)> == st::kDeletedKindCount);
  std::copy(std::begin(end->deleted), std::end(end->deleted), result.deleted.begin());
  return result;
}

}  // namespace oit::capture
