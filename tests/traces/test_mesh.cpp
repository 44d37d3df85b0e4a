// Mesh loaders (OBJ, OFF, ASCII PLY, gzip) on small inline files, their error
// messages, and the named-mesh table.
#include <gtest/gtest.h>
#include <unistd.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "traces/gen/Mesh.hpp"

namespace oit::gen {
namespace {

namespace fs = std::filesystem;
using Tri = std::array<uint32_t, 3>;

// A scratch directory per test process, removed at exit.
class MeshFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("oitsim_mesh_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  std::string writeGz(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    gzFile f = gzopen(path.c_str(), "wb");
    EXPECT_NE(f, nullptr);
    EXPECT_EQ(gzwrite(f, text.data(), static_cast<unsigned>(text.size())), static_cast<int>(text.size()));
    gzclose(f);
    return path;
  }
  // The message of the std::runtime_error fn throws ("" if none).
  template <class Fn>
  static std::string errorOf(Fn&& fn) {
    try {
      fn();
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  }

  fs::path dir_;
};

const char* kObj =
    "# a unit square as one quad, then a triangle by negative indices\n"
    "mtllib none.mtl\n"
    "o thing\n"
    "v 0 0 0\n"
    "v 1 0 0\n"
    "v 1 1 0\n"
    "v 0 1 0\n"
    "vt 0 0\n"
    "vn 0 0 1\n"
    "f 1/1/1 2/1/1 3/1/1 4/1/1\n"
    "v 0.5 0.5 2.5e-1\n"
    "s off\n"
    "f -1 -4//1 -3\n";

TEST_F(MeshFiles, ObjFanTriangulatesQuadsAndResolvesNegativeIndices) {
  Mesh m = loadMesh(write("square.obj", kObj));
  ASSERT_EQ(m.positions.size(), 5u);
  EXPECT_EQ(m.positions[4], (Vec3{0.5f, 0.5f, 0.25f}));
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Tri{0, 2, 3}));
  // -1 is the latest vertex (4), -4 the one three before it (1), -3 is 2.
  EXPECT_EQ(m.triangles[2], (Tri{4, 1, 2}));
}

TEST_F(MeshFiles, ObjErrorsNameFileAndLine) {
  const std::string p1 = write("bad1.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n");
  EXPECT_EQ(errorOf([&] { loadMesh(p1); }),
            p1 + ":5: face index 4 refers to a vertex not defined yet (3 so far)");
  const std::string p2 = write("bad2.obj", "v 0 0 0\nv 1 zero 0\n");
  EXPECT_EQ(errorOf([&] { loadMesh(p2); }), p2 + ":2: vertex coordinate 'zero' is not a number");
  const std::string p3 = write("bad3.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  EXPECT_EQ(errorOf([&] { loadMesh(p3); }),
            p3 + ":4: face index 0 is invalid (OBJ indices start at 1)");
  const std::string p4 = write("bad4.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n");
  EXPECT_EQ(errorOf([&] { loadMesh(p4); }), p4 + ":3: face has 2 vertices, needs at least 3");
  const std::string p5 = write("empty.obj", "v 0 0 0\n");
  EXPECT_EQ(errorOf([&] { loadMesh(p5); }), "mesh file '" + p5 + "' has no faces");
}

TEST_F(MeshFiles, OffWithCommentsColoursAndAQuad) {
  Mesh m = loadMesh(write("shape.off",
                          "OFF\n"
                          "# vertices faces edges\n"
                          "5 2 0\n"
                          "\n"
                          "0 0 0\n1 0 0\n1 1 0\n0 1 0  # corner\n"
                          "0.5 0.5 -1\n"
                          "4 0 1 2 3 255 0 0\n"
                          "3 4 1 0\n"));
  ASSERT_EQ(m.positions.size(), 5u);
  EXPECT_EQ(m.positions[4], (Vec3{0.5f, 0.5f, -1.0f}));
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Tri{0, 2, 3}));
  EXPECT_EQ(m.triangles[2], (Tri{4, 1, 0}));
  // Counts on the header line are accepted too.
  Mesh n = loadMesh(write("one.off", "OFF 3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_EQ(n.triangles.size(), 1u);
}

TEST_F(MeshFiles, OffErrorsNameFileAndLine) {
  const std::string p1 = write("short.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n");
  EXPECT_EQ(errorOf([&] { loadMesh(p1); }), p1 + ":4: file ends early: expected 4 vertices, got 2");
  const std::string p2 = write("range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  EXPECT_EQ(errorOf([&] { loadMesh(p2); }), p2 + ":6: face index 3 is outside 0..2");
  const std::string p3 = write("magic.off", "PLY\n");
  EXPECT_EQ(errorOf([&] { loadMesh(p3); }), p3 + ":1: not an OFF file: header is 'PLY', expected OFF");
}

TEST_F(MeshFiles, AsciiPlySkipsExtraPropertiesAndElements) {
  Mesh m = loadMesh(write("scan.ply",
                          "ply\n"
                          "format ascii 1.0\n"
                          "comment made by hand\n"
                          "element vertex 4\n"
                          "property float x\n"
                          "property float y\n"
                          "property float z\n"
                          "property float confidence\n"
                          "element face 2\n"
                          "property list uchar int vertex_indices\n"
                          "property uchar flags\n"
                          "element edge 1\n"
                          "property int vertex1\n"
                          "property int vertex2\n"
                          "end_header\n"
                          "0 0 0 0.5\n"
                          "2 0 0 1\n"
                          "2 3 0 1\n"
                          "0 3 -1.5 1\n"
                          "3 0 1 2 7\n"
                          "4 0 1 2 3 0\n"
                          "0 1\n"));
  ASSERT_EQ(m.positions.size(), 4u);
  EXPECT_EQ(m.positions[3], (Vec3{0, 3, -1.5f}));
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_EQ(m.triangles[0], (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangles[1], (Tri{0, 1, 2}));
  EXPECT_EQ(m.triangles[2], (Tri{0, 2, 3}));
}

TEST_F(MeshFiles, BinaryPlyIsRefusedClearly) {
  const std::string p = write("bin.ply",
                              "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
                              "property float x\nend_header\n\x01\x02\x03\x04");
  EXPECT_EQ(errorOf([&] { loadMesh(p); }),
            p + ":2: only ASCII PLY is supported; this file is binary_little_endian");
}

TEST_F(MeshFiles, PlyErrorsNameFileAndLine) {
  const std::string p = write("trunc.ply",
                              "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                              "property float y\nproperty float z\nelement face 1\n"
                              "property list uchar int vertex_indices\nend_header\n"
                              "0 0 0\n1 0 0\n0 1 0\n3 0 1\n");
  EXPECT_EQ(errorOf([&] { loadMesh(p); }), p + ":13: list 'vertex_indices' announces 3 items but gives 2");
}

TEST_F(MeshFiles, GzipCompressedFilesOfEachFormatLoad) {
  Mesh obj = loadMesh(writeGz("square.obj.gz", kObj));
  EXPECT_EQ(obj.triangles.size(), 3u);
  EXPECT_EQ(obj.triangles[2], (Tri{4, 1, 2}));
  Mesh off = loadMesh(writeGz("tri.OFF.gz", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_EQ(off.triangles.size(), 1u);
  Mesh ply = loadMesh(writeGz("tri.ply.gz",
                              "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                              "property float y\nproperty float z\nelement face 1\n"
                              "property list uchar int vertex_index\nend_header\n"
                              "0 0 0\n1 0 0\n0 1 7\n3 2 1 0\n"));
  ASSERT_EQ(ply.triangles.size(), 1u);
  EXPECT_EQ(ply.triangles[0], (Tri{2, 1, 0}));
  EXPECT_EQ(ply.positions[2].z, 7.0f);
}

TEST_F(MeshFiles, CorruptGzipIsAReadErrorWithTheFileName) {
  // A valid gzip header followed by garbage: zlib reports a data error.
  std::string bytes = "\x1f\x8b\x08\x00\x00\x00\x00\x00\x00\x03";
  bytes += std::string(64, '\xff');
  const std::string p = write("junk.obj.gz", bytes);
  const std::string msg = errorOf([&] { loadMesh(p); });
  EXPECT_EQ(msg.rfind(p + ":1: read error", 0), 0u) << msg;
}

TEST_F(MeshFiles, UnknownExtensionAndMissingFile) {
  const std::string p = write("model.stl", "solid x\n");
  EXPECT_EQ(errorOf([&] { loadMesh(p); }),
            "mesh file '" + p + "': unknown format; expected .obj, .off or .ply (optionally .gz)");
  const std::string missing = (dir_ / "nope.obj").string();
  EXPECT_EQ(errorOf([&] { loadMesh(missing); }),
            "cannot open mesh file '" + missing + "': No such file or directory");
}

TEST_F(MeshFiles, BoundsCoverTheUsedVertices) {
  Mesh m = loadMesh(write("b.obj", "v -1 0 0\nv 3 0 0\nv 1 2 0\nv 100 100 100\nf 1 2 3\n"));
  MeshBounds b = meshBounds(m);
  EXPECT_EQ(b.min, (Vec3{-1, 0, 0}));
  EXPECT_EQ(b.max, (Vec3{3, 2, 0}));  // vertex 4 is used by no face
  EXPECT_EQ(b.centre, (Vec3{1, 1, 0}));
  EXPECT_FLOAT_EQ(b.radius, std::sqrt(5.0f));
}

TEST(NamedMeshes, MissingPackageFileNamesThePackage) {
  const std::vector<NamedMesh> table = {
      {"teapot", "/nonexistent/oitsim/teapot.obj", "oitsim-test-data", "a test entry"}};
  try {
    resolveMeshPath("teapot", table);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(),
                 "mesh 'teapot' needs /nonexistent/oitsim/teapot.obj, which is not installed: it "
                 "comes with the Debian package oitsim-test-data (apt-get install oitsim-test-data)");
  }
  try {
    resolveMeshPath("kettle", table);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(),
                 "mesh 'kettle' is neither an existing file nor a known mesh name (known names: "
                 "teapot)");
  }
}

TEST(NamedMeshes, DisplayNames) {
  EXPECT_EQ(meshDisplayName("bunny"), "bunny");
  EXPECT_EQ(meshDisplayName("/data/dragon_vrip_res2.ply.gz"), "dragon_vrip_res2");
  EXPECT_EQ(meshDisplayName("models/armadillo.off"), "armadillo");
}

TEST(NamedMeshes, BunnyFromGlmark2Data) {
  const NamedMesh* bunny = findNamedMesh("bunny");
  ASSERT_NE(bunny, nullptr);
  EXPECT_EQ(bunny->package, "glmark2-data");
  if (!fileReadable(bunny->path)) GTEST_SKIP() << bunny->path << " missing: apt-get install glmark2-data";
  EXPECT_EQ(resolveMeshPath("bunny"), bunny->path);
  Mesh m = loadMesh(bunny->path);
  EXPECT_EQ(m.triangles.size(), 69666u);
  EXPECT_EQ(m.positions.size(), 34835u);
}

}  // namespace
}  // namespace oit::gen
