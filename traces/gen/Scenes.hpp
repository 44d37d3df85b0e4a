// Synthetic scenes rendered by the software rasterizer into fragment traces, each a
// different stress pattern for an order-independent-transparency ROP.
//
// Every scene lives in a world where its transparent content fills roughly the unit
// sphere around the origin; the camera orbits the origin (azimuth 0 looks from +z,
// elevation lifts it). A scene is deterministic for a seed: all randomness comes
// from oit::gen::Rng streams named after the draw.
//
// Usage: build a SceneGenerator (validates the options, loads meshes), create the
// trace writer from its header() (the writer needs the draw table first), then
// generate() into it.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "traces/Fragment.hpp"
#include "traces/TraceIO.hpp"

namespace oit::gen {

enum class Shading { Constant, Lambert };

struct SceneOptions {
  uint32_t width = 1280, height = 720;
  uint64_t seed = 1;
  bool backdrop = false;  // opaque checkered wall + floor and an opaque pillar, drawn first
  uint32_t count = 0;     // main element count (quads, strands, cards, panes); 0 = scene default
  double density = 1;     // multiplies the count (default or given); mesh ignores both
  std::string mesh = "bunny";  // mesh scene: a named mesh or a .obj/.off/.ply[.gz] path
  std::optional<double> azimuth_deg;    // camera orbit; unset = scene default
  std::optional<double> elevation_deg;  // in [-89, 89]
  double distance = 0;                  // camera distance from the origin; 0 = fit the scene
  std::optional<double> fov_deg;        // vertical field of view, in (1, 170)
  std::optional<float> alpha;  // main transparent alpha (particles: peak; foliage: scales the texture)
  std::optional<std::array<float, 3>> colour;  // main colour; unset = scene's (often random)
  Shading shading = Shading::Lambert;          // mesh shading; alpha stays constant
  ColourEncoding encoding = ColourEncoding::Fp32;
};

struct SceneInfo {
  std::string name;
  std::string description;
  uint32_t default_count = 0;  // 0: the scene takes no count
  std::string count_unit;      // what --count counts
};

// The generator scenes, in a fixed order.
std::vector<SceneInfo> sceneCatalog();

struct GenResult {
  uint64_t fragments = 0;
  uint64_t primitives = 0;  // triangles submitted, including culled or clipped-away ones
  uint32_t draws = 0;
  std::vector<uint64_t> fragments_per_draw;  // indexed by draw id
  std::vector<uint64_t> primitives_per_draw;
};

struct ScenePlan;  // the generator's internal description of the draws

class SceneGenerator {
 public:
  // Throws std::invalid_argument for an unknown scene (listing the valid names) or
  // an option out of range, std::runtime_error for an unloadable mesh.
  SceneGenerator(const std::string& scene, const SceneOptions& opts);
  ~SceneGenerator();
  SceneGenerator(SceneGenerator&&) noexcept;
  SceneGenerator& operator=(SceneGenerator&&) noexcept;

  // Frame size, encoding, camera near/far and the draw table (ids 0..n-1).
  const TraceHeader& header() const;

  // Rasterizes every draw in order into sink (fragments in submission order: draw,
  // primitive, then bottom-to-top rows). progress gets fractions in [0, 1].
  // Does not commit the sink. May be called again; it produces the same stream.
  GenResult generate(FragmentSink& sink, const std::function<void(double)>& progress = {}) const;

 private:
  std::unique_ptr<ScenePlan> plan_;
};

// Conveniences over SceneGenerator.
TraceHeader sceneHeader(const std::string& scene, const SceneOptions& opts);
GenResult generateScene(const std::string& scene, const SceneOptions& opts, FragmentSink& sink,
                        const std::function<void(double)>& progress = {});

}  // namespace oit::gen
