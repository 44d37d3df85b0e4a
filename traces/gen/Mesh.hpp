// Triangle meshes for the generators: OBJ, OFF and ASCII PLY loaders (each also
// gzip-compressed, name.ext.gz) and a table of named meshes shipped by Debian packages.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "traces/gen/Math.hpp"

namespace oit::gen {

struct Mesh {
  std::string source;  // the file it was loaded from
  std::vector<Vec3> positions;
  std::vector<std::array<uint32_t, 3>> triangles;  // polygons fan-triangulated
};

// Axis-aligned bounds and the bounding sphere around their centre (of the
// vertices the triangles use).
struct MeshBounds {
  Vec3 min, max;
  Vec3 centre;
  float radius = 0;
};
MeshBounds meshBounds(const Mesh& mesh);

// Loads by extension: .obj, .off, .ply, each optionally followed by .gz.
// Throws std::runtime_error naming the file (and line, for content errors).
Mesh loadMesh(const std::string& path);

// The format parsers, for callers that know the format regardless of the name.
Mesh loadObj(const std::string& path);
Mesh loadOff(const std::string& path);
Mesh loadPly(const std::string& path);

// A mesh known by name, its file, and the Debian package that installs it.
struct NamedMesh {
  std::string name;
  std::string path;
  std::string package;
  std::string description;
};
const std::vector<NamedMesh>& namedMeshes();
const NamedMesh* findNamedMesh(std::string_view name,
                               const std::vector<NamedMesh>& table = namedMeshes());
bool fileReadable(const std::string& path);
// How to install a named mesh's file: "apt-get install PACKAGE" or the script to run.
std::string meshInstallHint(const NamedMesh& m);

// A named mesh's path, or the argument itself when it names no mesh. Throws
// std::runtime_error when a named mesh's file is missing (saying which package
// provides it) or when the argument is neither a name nor an existing file.
std::string resolveMeshPath(const std::string& name_or_path,
                            const std::vector<NamedMesh>& table = namedMeshes());

// The draw-table name for a mesh argument: the name itself, or the file name
// without directories and extensions ("dragon_vrip" for .../dragon_vrip.ply.gz).
std::string meshDisplayName(const std::string& name_or_path);

}  // namespace oit::gen
