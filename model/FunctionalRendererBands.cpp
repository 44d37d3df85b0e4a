// FunctionalRenderer::renderInBands: the exact reference within a memory
// limit (see FunctionalRenderer.hpp). The band file holds the fragments that
// reach the algorithm, grouped by band, each band in submission order.
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

#include "model/FunctionalRenderer.hpp"
#include "traces/InputFile.hpp"

namespace oit::model {

namespace {

constexpr size_t kReadChunk = size_t(1) << 16;          // fragments per read of the band file (2 MiB)
constexpr uint64_t kWriteBuffers = uint64_t(8) << 20;  // bytes of all bands' write buffers together

std::string gib(uint64_t bytes) { return fmt::format("{:.2f} GiB", double(bytes) / double(uint64_t(1) << 30)); }

// An unnamed file in `dir` (O_TMPFILE); where the file system lacks it, a
// named one removed at once. Either way nothing stays behind once it is
// closed, whatever ends the process.
FileDescriptor bandFile(const std::string& dir) {
#ifdef O_TMPFILE
  const int fd = ::open(dir.c_str(), O_TMPFILE | O_RDWR | O_CLOEXEC, 0600);
  if (fd >= 0) return FileDescriptor(fd);
#endif
  std::string name = (dir.empty() ? std::string(".") : dir) + "/.oitsim-bands.XXXXXX";
  const int named = ::mkostemp(name.data(), O_CLOEXEC);
  if (named < 0)
    throw std::runtime_error(
        fmt::format("{}: cannot create the reference's temporary band file: {}", dir, std::strerror(errno)));
  ::unlink(name.c_str());
  return FileDescriptor(named);
}

void writeAt(int fd, const void* data, size_t n, uint64_t at, const std::string& dir) {
  const auto* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t k = ::pwrite(fd, p, n, off_t(at));
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0)
      throw std::runtime_error(fmt::format("{}: cannot write the reference's temporary band file: {}", dir,
                                           k < 0 ? std::strerror(errno) : "no space written"));
    p += k;
    at += uint64_t(k);
    n -= size_t(k);
  }
}

size_t readAt(int fd, void* data, size_t n, uint64_t at, const std::string& dir) {
  auto* p = static_cast<char*>(data);
  size_t done = 0;
  while (done < n) {
    const ssize_t k = ::pread(fd, p + done, n - done, off_t(at + done));
    if (k < 0 && errno == EINTR) continue;
    if (k < 0)
      throw std::runtime_error(
          fmt::format("{}: cannot read the reference's temporary band file: {}", dir, std::strerror(errno)));
    if (k == 0) break;
    done += size_t(k);
  }
  return done;
}

// The band file: band b's fragments at [first[b], first[b] + count[b]) in
// fragments, written through one small buffer per band.
class BandFile {
 public:
  BandFile(const std::string& dir, const std::vector<uint64_t>& count)
      : dir_(dir), fd_(bandFile(dir)), first_(count.size()), written_(count.size(), 0), count_(count) {
    uint64_t total = 0;
    for (size_t b = 0; b < count.size(); ++b) {
      first_[b] = total;
      total += count[b];
    }
    bytes_ = total * sizeof(Fragment);
    struct statvfs vfs {};
    if (::fstatvfs(fd_.get(), &vfs) == 0) {
      const uint64_t free_bytes = uint64_t(vfs.f_bavail) * vfs.f_frsize;
      if (free_bytes < bytes_)
        throw std::runtime_error(fmt::format(
            "{}: the reference needs {} of disk space for its temporary band file ({} fragments in {} bands), {} "
            "are free",
            dir_, gib(bytes_), total, count.size(), gib(free_bytes)));
    }
    // Claims the space now where the file system can (a later write cannot
    // then fail for lack of it); where it cannot, the writes check.
    if (bytes_ > 0 && ::fallocate(fd_.get(), 0, 0, off_t(bytes_)) != 0 && errno == ENOSPC)
      throw std::runtime_error(fmt::format("{}: no space for the reference's temporary band file of {}", dir_,
                                           gib(bytes_)));
    const uint64_t per_band = std::max<uint64_t>(64, kWriteBuffers / sizeof(Fragment) / std::max<size_t>(1, count.size()));
    cap_ = size_t(per_band);
    buffers_.resize(count.size());
  }
  uint64_t bytes() const { return bytes_; }

  // Throws when band b gets more fragments than the counting pass found.
  void append(size_t b, const Fragment& f) {
    std::vector<Fragment>& buf = buffers_[b];
    if (buf.capacity() == 0) buf.reserve(cap_);
    buf.push_back(f);
    if (buf.size() == cap_) flush(b);
  }
  void flushAll() {
    for (size_t b = 0; b < buffers_.size(); ++b) {
      flush(b);
      std::vector<Fragment>().swap(buffers_[b]);
    }
  }
  // Calls f(fragment) for band b's fragments, in the order they were appended.
  template <class F>
  void forEach(size_t b, F&& f) {
    std::vector<Fragment> chunk(std::min<uint64_t>(kReadChunk, std::max<uint64_t>(1, written_[b])));
    for (uint64_t done = 0; done < written_[b];) {
      const size_t n = size_t(std::min<uint64_t>(chunk.size(), written_[b] - done));
      const size_t got = readAt(fd_.get(), chunk.data(), n * sizeof(Fragment), (first_[b] + done) * sizeof(Fragment), dir_);
      if (got != n * sizeof(Fragment))
        throw std::runtime_error(fmt::format("{}: the reference's temporary band file ends early", dir_));
      for (size_t i = 0; i < n; ++i) f(chunk[i]);
      done += n;
    }
  }

 private:
  void flush(size_t b) {
    std::vector<Fragment>& buf = buffers_[b];
    if (buf.empty()) return;
    if (written_[b] + buf.size() > count_[b])
      throw std::runtime_error("the trace changed while it was read: a band has more fragments than when counted");
    writeAt(fd_.get(), buf.data(), buf.size() * sizeof(Fragment), (first_[b] + written_[b]) * sizeof(Fragment), dir_);
    written_[b] += buf.size();
    buf.clear();
  }

  std::string dir_;
  FileDescriptor fd_;
  std::vector<uint64_t> first_, written_;
  const std::vector<uint64_t>& count_;
  std::vector<std::vector<Fragment>> buffers_;
  size_t cap_ = 64;
  uint64_t bytes_ = 0;
};

}  // namespace

std::vector<uint64_t> planBands(const std::vector<uint32_t>& fragments_per_pixel, uint32_t width,
                                uint64_t bytes_per_pixel, uint64_t bytes_per_fragment, uint64_t limit) {
  std::vector<uint64_t> first{0};
  uint64_t used = 0;
  for (size_t p = 0; p < fragments_per_pixel.size(); ++p) {
    const uint64_t need = bytes_per_pixel + uint64_t(fragments_per_pixel[p]) * bytes_per_fragment;
    if (need > limit)
      throw std::runtime_error(fmt::format(
          "pixel ({}, {}) alone holds {} fragments for the reference, {} bytes, more than the {} bytes one band "
          "may take",
          p % width, p / width, fragments_per_pixel[p], need, limit));
    if (used + need > limit) {
      first.push_back(p);
      used = 0;
    }
    used += need;
  }
  return first;
}

BandedRender FunctionalRenderer::renderInBands(FragmentSource& src, OitAlgorithm& algo, const BandOptions& bo) const {
  if (algo.passes() != 1) throw std::logic_error("renderInBands: only single-pass algorithms render in bands");
  const TraceHeader& h = src.header();
  const DrawClassifier classes(h);
  algo.beginFrame(h);  // its checks, before any pass
  const uint32_t w = h.width;
  const size_t pixels = size_t(w) * h.height;
  const unsigned words = algo.stateWords();
  const uint64_t bpp = algo.bytesPerPixel(), bpf = algo.poolBytesPerFragment();

  BandedRender out;
  RenderCounts& counts = out.result.counts;
  counts.pass_outcomes.assign(1, {});
  // Passes over the trace: opaque (if any), counting (unless the trace's
  // fragment count shows the frame fits), then one that feeds the algorithm
  // (one band) or fills the band file; then the bands from the band file.
  const OpaqueLayer opaque = buildOpaqueLayer(src, classes);
  if (classes.anyOpaque()) ++counts.source_passes;

  const bool fits = bpf == 0 || h.fragment_count <= (bo.limit_bytes >= pixels * bpp ? bo.limit_bytes - pixels * bpp : 0) / bpf;
  // Progress steps: the opaque pass, then counting + band file + the bands, or one pass.
  const unsigned steps = (classes.anyOpaque() ? 1u : 0u) + (fits ? 1u : 3u);
  unsigned step = classes.anyOpaque() ? 1u : 0u;
  auto report = [&](std::string_view what, uint64_t done, uint64_t total) {
    if (opt_.progress) opt_.progress({step, steps, what, done, total});
  };
  // The fragments of one read of the trace that reach the algorithm: f(fragment, pixel).
  auto readTrace = [&](std::string_view what, auto&& f) {
    src.rewind();
    ++counts.source_passes;
    uint64_t index = 0, opaque_seen = 0, culled = 0, next_report = opt_.progress_every;
    DrawRun draws(classes);
    for (auto batch = src.next(); !batch.empty(); batch = src.next()) {
      for (const Fragment& fr : batch) {
        if (fr.x >= w || fr.y >= h.height) [[unlikely]]
          detail::fragmentOutsideFrame(src, index, fr, w, h.height);
        const size_t p = size_t(fr.y) * w + fr.x;
        ++index;
        if (draws.isOpaque(fr.draw)) {
          ++opaque_seen;
          continue;
        }
        if (fr.z >= opaque.depth[p]) {
          ++culled;
          continue;
        }
        f(fr, p);
      }
      if (opt_.progress && index >= next_report) {
        report(what, index, h.fragment_count);
        next_report = index + opt_.progress_every;
      }
    }
    report(what, index, h.fragment_count);
    ++step;
    counts.fragments_in = index;
    counts.opaque = opaque_seen;
    counts.culled = culled;
  };

  std::vector<uint64_t> first{0};
  std::vector<uint64_t> band_fragments;
  if (fits) {
    band_fragments = {h.fragment_count};
  } else {
    std::vector<uint32_t> per_pixel(pixels, 0);
    readTrace("count", [&](const Fragment&, size_t p) {
      if (per_pixel[p] != UINT32_MAX) ++per_pixel[p];
    });
    first = planBands(per_pixel, w, bpp, bpf, bo.limit_bytes);
    band_fragments.assign(first.size(), 0);
    for (size_t b = 0; b < first.size(); ++b) {
      const size_t end = b + 1 < first.size() ? size_t(first[b + 1]) : pixels;
      for (size_t p = size_t(first[b]); p < end; ++p) band_fragments[b] += per_pixel[p];
    }
  }
  out.bands = unsigned(first.size());
  first.push_back(pixels);

  Image img(w, h.height);
  auto& outcomes = counts.pass_outcomes[0];
  const OitAlgorithm::InsertFn insert = algo.insertFn();
  // One band: its state, every fragment of `feed`, the resolve of its pixels.
  auto renderBand = [&](size_t b, auto&& feed) {
    const size_t p0 = size_t(first[b]), p1 = size_t(first[b + 1]);
    algo.reservePool(band_fragments[b]);  // exact: no doubling
    algo.beginFrame(h);
    StateBuffer state((p1 - p0) * words);
    algo.clearFrame(state.data(), p1 - p0);
    InsertContext ctx;
    feed([&](const Fragment& f, size_t p) {
      ctx.opaque_z = opaque.depth[p];
      ++outcomes[size_t(insert(algo, state.data() + (p - p0) * words, f, 0, ctx))];
    });
    out.largest_band_bytes = std::max(out.largest_band_bytes, uint64_t(p1 - p0) * bpp + algo.poolBytes());
    for (size_t p = p0; p < p1; ++p) {
      const Rgb bg = opaque.landed(p) ? opaque.colour[p] : opt_.clear_colour;
      img.pixels[p] = algo.resolve(state.data() + (p - p0) * words, bg);
    }
  };

  if (out.bands == 1) {
    renderBand(0, [&](auto&& insertOne) { readTrace(algo.passName(0), insertOne); });
  } else {
    BandFile file(bo.spill_dir, band_fragments);
    out.spill_bytes = file.bytes();
    size_t last = 0;  // fragments come in runs: try the last band first
    readTrace("bands", [&](const Fragment& f, size_t p) {
      if (p < first[last] || p >= first[last + 1])
        last = size_t(std::upper_bound(first.begin(), first.end() - 1, uint64_t(p)) - first.begin()) - 1;
      file.append(last, f);
    });
    file.flushAll();
    for (size_t b = 0; b + 1 < first.size(); ++b) {
      report("bands", b, out.bands);
      renderBand(b, [&](auto&& insertOne) {
        file.forEach(b, [&](const Fragment& f) { insertOne(f, size_t(f.y) * w + f.x); });
      });
    }
  }

  counts.stored = outcomes[size_t(InsertOutcome::Stored)];
  counts.merged = outcomes[size_t(InsertOutcome::Merged)];
  counts.discarded = outcomes[size_t(InsertOutcome::Discarded)];
  for (unsigned o = 0; o < kOutcomeCount; ++o) {
    counts.bytes_read += outcomes[o] * algo.readBytes(0, InsertOutcome(o));
    counts.bytes_written += outcomes[o] * algo.writeBytes(0, InsertOutcome(o));
  }
  out.result.image = std::move(img);
  out.result.state_bytes = out.largest_band_bytes;
  return out;
}

}  // namespace oit::model
