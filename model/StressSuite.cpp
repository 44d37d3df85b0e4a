// The stress suite's runner (model/StressSuite.hpp): every configuration of
// every algorithm, format and k over the cases (StressCases.cpp), each image
// checked for NaN, Inf and range; the tables are written by StressTables.cpp.
#include "model/StressSuite.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>

#include "model/MemorySource.hpp"

namespace oit::model::stress {

namespace {

const char* kFormatNames[] = {"fp32", "rgba8t8z32", "fp16"};
constexpr std::array<StorageFormat, 3> kFormats{StorageFormat::Fp32, StorageFormat::Rgba8T8Z32, StorageFormat::Fp16};

// Everything but the makeAlgorithm rejection is recorded as an Error row.
std::unique_ptr<OitAlgorithm> tryMake(const std::string& algo, const AlgorithmParams& p, std::string& why) {
  try {
    return makeAlgorithm(algo, p);
  } catch (const std::invalid_argument& e) {
    why = e.what();
    return nullptr;
  }
}

void evaluate(const StressCase& c, const Image& ref, const std::vector<char>& covered, OitAlgorithm& a, StressRow& row) {
  row.bytes_per_pixel = a.bytesPerPixel();
  RenderResult r;
  try {
    r = renderCase(c, a);
  } catch (const std::exception& e) {
    row.status = RowStatus::Error;
    row.note = std::string("render threw: ") + e.what();
    return;
  }
  const RenderCounts& n = r.counts;
  row.stored = n.stored;
  row.merged = n.merged;
  row.discarded = n.discarded;
  row.culled = n.culled;
  row.balanced = n.balanced();
  for (const auto& pass : n.pass_outcomes)
    if (pass[0] + pass[1] + pass[2] + n.opaque + n.culled != n.fragments_in) row.balanced = false;

  double maxErr = 0, sq = 0;
  uint64_t samples = 0;
  bool haveFinite = false;
  std::string worst;
  double worstDist = 0;
  for (uint32_t y = 0; y < r.image.height; ++y)
    for (uint32_t x = 0; x < r.image.width; ++x) {
      const size_t i = r.image.index(x, y);
      const Rgb& p = r.image.pixels[i];
      const Rgb& q = ref.pixels[i];
      const float v[3] = {p.r, p.g, p.b}, w[3] = {q.r, q.g, q.b};
      for (int ch = 0; ch < 3; ++ch) {
        if (!std::isfinite(v[ch])) {
          if (row.non_finite++ == 0) worst = fmt::format("{} at ({},{}) ch {}", v[ch], x, y, ch);
          worstDist = std::numeric_limits<double>::infinity();
          continue;
        }
        row.min_value = haveFinite ? std::min(row.min_value, double(v[ch])) : double(v[ch]);
        row.max_value = haveFinite ? std::max(row.max_value, double(v[ch])) : double(v[ch]);
        haveFinite = true;
        if (!(v[ch] >= 0.0f && v[ch] <= 1.0f)) {
          ++row.out_of_range;
          const double dist = v[ch] < 0.0f ? -double(v[ch]) : double(v[ch]) - 1.0;
          if (dist > worstDist) {
            worstDist = dist;
            worst = fmt::format("{:.9g} at ({},{}) ch {}", v[ch], x, y, ch);
          }
        }
        const double e = std::abs(double(v[ch]) - double(w[ch]));
        maxErr = std::max(maxErr, e);
        if (covered[i]) {
          sq += e * e;
          ++samples;
        }
      }
    }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  row.max_abs_error = row.non_finite ? nan : maxErr;
  row.rmse = row.non_finite ? nan : (samples ? std::sqrt(sq / double(samples)) : 0.0);

  std::string why;
  if (row.non_finite) why += fmt::format("{} non-finite channel(s), first {}; ", row.non_finite, worst);
  else if (row.out_of_range) why += fmt::format("{} channel(s) outside [0,1], worst {}; ", row.out_of_range, worst);
  if (!row.balanced)
    why += fmt::format("outcomes unbalanced (in {}, opaque {}, culled {}, stored {}, merged {}, discarded {}); ",
                       n.fragments_in, n.opaque, n.culled, n.stored, n.merged, n.discarded);
  if (!why.empty()) {
    why.resize(why.size() - 2);
    row.status = RowStatus::Violation;
    row.note = why;
  }
}

}  // namespace

const char* toString(RowStatus s) {
  switch (s) {
    case RowStatus::Ok: return "ok";
    case RowStatus::NotApplicable: return "n/a";
    case RowStatus::Violation: return "VIOLATION";
    case RowStatus::Error: return "ERROR";
  }
  return "?";
}

RenderResult renderCase(const StressCase& c, OitAlgorithm& algo) {
  MemorySource src(c.header, c.fragments, 1000);
  RenderOptions o;
  o.clear_colour = c.clear;
  return FunctionalRenderer(o).render(src, algo);
}

std::vector<StressConfig> stressConfigs() {
  std::vector<StressConfig> out;
  for (const AlgorithmInfo& info : algorithmNames()) {
    const std::string name(info.name);
    AlgorithmParams p;
    if (name == "wboit") {
      for (int eq : {7, 8, 9, 10}) {
        p.weight = eq;
        // eq. 7-9 read the planes from the trace header; give them here too.
        p.camera = CameraPlanes{kNear, kFar};
        out.push_back({name, fmt::format("eq{}", eq), p});
      }
    } else if (name == "slab") {
      p.bits = 8;
      out.push_back({name, "b8", p});
      p.coverage_mask = true;
      p.bits = 32;
      out.push_back({name, "mask-b32", p});
    } else if (name == "stochastic") {
      for (unsigned samples : {8u, 64u}) {
        p.samples = samples;
        out.push_back({name, fmt::format("S{}", samples), p});
      }
    } else {
      out.push_back({name, "", p});
    }
  }
  return out;
}

std::vector<StressRow> runStress(const StressOptions& opt) {
  std::vector<StressConfig> configs;
  const std::vector<StressConfig> all = stressConfigs();
  if (opt.algorithms.empty()) {
    configs = all;
  } else {
    for (const std::string& a : opt.algorithms) {
      bool found = false;
      for (const StressConfig& c : all)
        if (c.algorithm == a) {
          configs.push_back(c);
          found = true;
        }
      if (!found) makeAlgorithm(a, AlgorithmParams{});  // throws naming the valid algorithms
      if (!found) throw std::invalid_argument("unknown OIT algorithm '" + a + "'");
    }
  }
  const std::vector<std::string>& cases = opt.cases.empty() ? caseNames() : opt.cases;
  for (const std::string& name : cases) (void)makeCase(name);  // validate every name first

  std::vector<StressRow> rows;
  for (const std::string& name : cases) {
    if (opt.on_case) opt.on_case(name);
    const StressCase c = makeCase(name);
    auto refAlgo = makeAlgorithm("abuffer", AlgorithmParams{});
    const Image ref = renderCase(c, *refAlgo).image;
    std::vector<char> covered(size_t(c.header.width) * c.header.height, 0);
    for (const Fragment& f : c.fragments) covered[size_t(f.y) * c.header.width + f.x] = 1;

    for (const StressConfig& cfg : configs)
      for (size_t fi = 0; fi < kFormats.size(); ++fi) {
        StressRow base;
        base.case_name = c.name;
        base.algorithm = cfg.algorithm;
        base.variant = cfg.variant;
        base.format = kFormatNames[fi];
        base.fragments = c.fragments.size();
        AlgorithmParams p = cfg.params;
        p.format = kFormats[fi];

        // Does the state depend on k? Probe two sizes: if the layout is the
        // same, the algorithm has no k and runs once (k shown as "-").
        std::string why2, why3;
        AlgorithmParams p2 = p, p3 = p;
        p2.layers = 2;
        p3.layers = 3;
        auto a2 = tryMake(cfg.algorithm, p2, why2);
        auto a3 = tryMake(cfg.algorithm, p3, why3);
        if (!a2 && !a3) {
          StressRow r = base;
          r.status = RowStatus::NotApplicable;
          r.note = why2;
          rows.push_back(r);
          continue;
        }
        const bool usesK = !(a2 && a3 && a2->stateWords() == a3->stateWords());
        std::vector<unsigned> ks = usesK ? opt.layers : std::vector<unsigned>{0};
        for (unsigned k : ks) {
          StressRow r = base;
          r.k = k;
          AlgorithmParams pk = p;
          if (k) pk.layers = k;
          std::string why;
          auto a = tryMake(cfg.algorithm, pk, why);
          if (!a) {
            r.status = RowStatus::NotApplicable;
            r.note = why;
          } else {
            evaluate(c, ref, covered, *a, r);
          }
          rows.push_back(std::move(r));
        }
      }
  }
  return rows;
}

}  // namespace oit::model::stress
