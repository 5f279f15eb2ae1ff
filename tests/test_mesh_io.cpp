// Mesh readers and writers: every format is generated here, in a temporary directory, so
// no binary fixture lives in the repository.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "core/atomic_file.h"
#include "core/mesh_io.h"
#include "tests/test_support.h"

namespace chordfit {
namespace {

namespace fs = std::filesystem;

// Positions that went through a float (binary STL, VTK "float") are compared at float
// resolution; everything else must come back bit for bit.
constexpr double kFloatTolerance = 1e-6;

class MeshIoTest : public ::testing::Test {
 protected:
  fs::path write(const std::string& name, const std::string& bytes) const {
    const fs::path path = dir_ / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }

  std::string read(const fs::path& path) const {
    std::string bytes;
    EXPECT_TRUE(readWholeFile(path, bytes));
    return bytes;
  }

  // Writes `bytes` to a fresh file, reads it and deletes it. A fresh name per call matters:
  // truncating and rewriting one file makes ext4 flush it on close, 40x slower.
  bool readFresh(const std::string& extension, const std::string& bytes, Diagnostics& diagnostics) {
    const fs::path path = write("fresh" + std::to_string(fresh_++) + extension, bytes);
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    const bool ok = readMesh(path, V, F, diagnostics);
    fs::remove(path);
    return ok;
  }

  // Reads 1000 copies of `bytes`, each with `flips` random bytes overwritten (seeded, so a
  // failure reproduces): whatever the reader makes of a copy, it must not crash, and it must
  // succeed exactly when it reports no problem.
  void expectCorruptedCopiesReadConsistently(const std::string& extension, const std::string& bytes,
                                             unsigned seed, int flips) {
    std::mt19937 rng(seed);
    for (int trial = 0; trial < 1000; ++trial) {
      std::string corrupt = bytes;
      for (int flip = 0; flip < flips; ++flip)
        corrupt[rng() % corrupt.size()] = static_cast<char>(rng() & 0xff);
      Diagnostics diagnostics;
      const bool ok = readFresh(extension, corrupt, diagnostics);
      EXPECT_EQ(ok, diagnostics.ok());
    }
  }

  // Reads and expects success; prints the diagnostics otherwise.
  void readOk(const fs::path& path, Eigen::MatrixXd& V, Eigen::MatrixXi& F) const {
    Diagnostics diagnostics;
    const bool ok = readMesh(path, V, F, diagnostics, path.filename().string());
    std::ostringstream messages;
    diagnostics.print(messages);
    ASSERT_TRUE(ok) << messages.str();
    EXPECT_TRUE(diagnostics.ok());
  }

  // Reads `path` and expects the unit quad of kQuadPositions, fan-triangulated where the
  // format has polygons: quadVertices() in the two triangles squareFaces().
  void expectReadsAsTheQuad(const fs::path& path) const;

  // Reads and expects a reported failure; returns the single problem.
  Problem readFails(const fs::path& path) const {
    Diagnostics diagnostics;
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    EXPECT_FALSE(readMesh(path, V, F, diagnostics, "mesh"));
    EXPECT_EQ(diagnostics.problems().size(), 1u);
    EXPECT_EQ(V.rows(), 0);
    EXPECT_EQ(F.rows(), 0);
    return diagnostics.problems().empty() ? Problem{} : diagnostics.problems().front();
  }

  testing::TempDir temp_;
  const fs::path dir_ = temp_.path();
  int fresh_ = 0;
};

// A unit square split into two triangles, with awkward coordinates that need all 17
// significant digits.
Eigen::MatrixXd squareVertices() {
  return Eigen::MatrixXd{{0.1, 0.2, 1.0 / 3.0},
                         {1.0 + 1e-15, 0.0, -2.5e-300},
                         {1.0, 1.0, 123456.789012345678},
                         {-0.0, 1.0, 1e300}};
}
Eigen::MatrixXi squareFaces() { return Eigen::MatrixXi{{0, 1, 2}, {0, 2, 3}}; }

// The same square as one quad: readers must fan-triangulate it to squareFaces().
const char* kQuadPositions = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n";
Eigen::MatrixXd quadVertices() {
  return Eigen::MatrixXd{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
}

void MeshIoTest::expectReadsAsTheQuad(const fs::path& path) const {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(path, V, F);
  EXPECT_EQ(V, quadVertices());
  EXPECT_EQ(F, squareFaces());
}

// --- binary helpers ---------------------------------------------------------------------

template <typename T>
void appendBigEndian(std::string& out, T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  for (std::size_t i = 0; i < sizeof(T); ++i) out += static_cast<char>(bytes[sizeof(T) - 1 - i]);
}

template <typename T>
void appendLittleEndian(std::string& out, T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  for (std::size_t i = 0; i < sizeof(T); ++i) out += static_cast<char>(bytes[i]);
}

std::string binaryStl(const std::string& header80, const std::vector<Eigen::Matrix3f>& facets) {
  std::string out = header80;
  out.resize(80, ' ');
  appendLittleEndian<std::uint32_t>(out, static_cast<std::uint32_t>(facets.size()));
  for (const Eigen::Matrix3f& f : facets) {
    for (int k = 0; k < 3; ++k) appendLittleEndian<float>(out, 0.0f);  // normal
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) appendLittleEndian<float>(out, f(r, k));
    out += std::string(2, '\0');
  }
  return out;
}

// --- PLY ----------------------------------------------------------------------------------

TEST_F(MeshIoTest, PlyWrittenByWritePlyReadsBackBitExact) {
  const fs::path path = dir_ / "square.ply";
  Eigen::VectorXd deviation(4);
  deviation << 0.5, std::nan(""), -1.25, 3.0;
  writePly(path, squareVertices(), squareFaces(),
           {{"deviation mm", deviation}, {"label", Eigen::VectorXd::Ones(4)}});
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(path, V, F);
  ASSERT_EQ(V.rows(), 4);
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(std::memcmp(&V(i, k), &squareVertices()(i, k), sizeof(double)), 0)
          << "vertex " << i << " axis " << k;
  EXPECT_EQ(F, squareFaces());
}

TEST_F(MeshIoTest, PlyHeaderNamesEveryScalarFieldWithSpacesReplaced) {
  const fs::path path = dir_ / "fields.ply";
  writePly(path, squareVertices(), squareFaces(), {{"deviation mm", Eigen::VectorXd::Zero(4)}});
  const std::string bytes = read(path);
  const std::string header = bytes.substr(0, bytes.find("end_header"));
  EXPECT_NE(header.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_NE(header.find("property double x\n"), std::string::npos);
  EXPECT_NE(header.find("property float deviation_mm\n"), std::string::npos);
  EXPECT_NE(header.find("property list uchar int vertex_indices\n"), std::string::npos);
}

TEST_F(MeshIoTest, AsciiPlyQuadIsFanTriangulated) {
  const fs::path path =
      write("quad.ply", std::string("ply\nformat ascii 1.0\ncomment hand-made\n"
                                    "element vertex 4\nproperty float x\nproperty float y\n"
                                    "property float z\nproperty uchar red\n"
                                    "element face 1\nproperty list uchar int vertex_indices\n"
                                    "end_header\n") +
                            "0 0 0 1\n1 0 0 2\n1 1 0 3\n0 1 0 4\n4 0 1 2 3\n");
  expectReadsAsTheQuad(path);
}

TEST_F(MeshIoTest, BigEndianPlyWithVertexIndexListIsRead) {
  std::string bytes =
      "ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\n"
      "property double y\nproperty double z\nelement face 1\n"
      "property list uchar uint vertex_index\nend_header\n";
  const Eigen::MatrixXd quad = quadVertices();
  for (Eigen::Index i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) appendBigEndian<double>(bytes, quad(i, k));
  bytes += static_cast<char>(4);
  for (std::uint32_t v : {0u, 1u, 2u, 3u}) appendBigEndian<std::uint32_t>(bytes, v);
  expectReadsAsTheQuad(write("big.ply", bytes));
}

TEST_F(MeshIoTest, UppercaseExtensionIsAccepted) {
  const fs::path path = dir_ / "SQUARE.PLY";
  writePly(path, squareVertices(), squareFaces());
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(path, V, F);
  EXPECT_EQ(F.rows(), 2);
}

TEST_F(MeshIoTest, OutOfRangeAndNegativePlyIndicesAreCopiedForTheValidator) {
  const fs::path path = write("bad_index.ply",
                              "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                              "property double y\nproperty double z\nelement face 2\n"
                              "property list uchar int vertex_indices\nend_header\n"
                              "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n3 0 -1 2\n");
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(path, V, F);
  EXPECT_EQ(F, (Eigen::MatrixXi{{0, 1, 7}, {0, -1, 2}}));
}

TEST_F(MeshIoTest, BinaryPlyKeepsNanCoordinatesForTheValidator) {
  Eigen::MatrixXd V0 = squareVertices();
  V0(2, 1) = std::numeric_limits<double>::quiet_NaN();
  const fs::path path = dir_ / "nan.ply";
  writePly(path, V0, squareFaces());
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(path, V, F);
  EXPECT_TRUE(std::isnan(V(2, 1)));
}

TEST_F(MeshIoTest, AsciiPlyWithNanIsRefusedWithAnExplanation) {
  const fs::path path = write("nan_ascii.ply",
                              "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                              "property double y\nproperty double z\nelement face 1\n"
                              "property list uchar int vertex_indices\nend_header\n"
                              "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n");
  const Problem p = readFails(path);
  EXPECT_NE(p.what.find("non-finite"), std::string::npos) << p.what;
}

TEST_F(MeshIoTest, MalformedPlyHeadersAreReportedNotCrashedOn) {
  const std::string vertex_props = "property double x\nproperty double y\nproperty double z\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      // CGAL would index an empty element list here.
      {"ply\nformat ascii 1.0\nproperty float x\nend_header\n", "property before any element"},
      // CGAL would dereference a null pointer for an integer x.
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty int x\nproperty int y\n"
       "property int z\nend_header\n1 2 3\n",
       "must be float or double"},
      {"ply\nformat ascii 1.0\nelement vertex 1\n" + vertex_props, "end_header"},
      {"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n" + vertex_props +
           "end_header\n",
       "larger than the file"},
      {"ply\nformat binary_little_endian 1.0\nelement vertex 2\n" + vertex_props + "end_header\n" +
           std::string(30, '\0'),
       "element vertex 1: file is truncated"},
      {"ply\nformat ascii 1.0\nelement vertex 1\n" + vertex_props +
           "element face 1\nproperty list int int vertex_indices\nend_header\n0 0 0\n"
           "2000000000 0 0 0\n",
       "runs past the end"},
      {"ply\nformat ascii 1.0\nelement vertex 0\n" + vertex_props +
           "element junk 999999999999999\nend_header\n",
       "larger than the file"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty quux x\nend_header\n",
       "unknown property type"},
      {"not a ply at all", "not a PLY file"},
  };
  for (const auto& [text, expected] : cases) {
    const Problem p = readFails(write("bad.ply", text));
    EXPECT_NE((p.where + ": " + p.what).find(expected), std::string::npos)
        << "got '" << p.where << ": " << p.what << "' for:\n"
        << text;
  }
}

TEST_F(MeshIoTest, BinaryPlyListLengthPastTheEndIsReported) {
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
      "property float y\nproperty float z\nelement face 1\n"
      "property list uint int vertex_indices\nend_header\n";
  for (int k = 0; k < 3; ++k) appendLittleEndian<float>(bytes, 0.0f);
  appendLittleEndian<std::uint32_t>(bytes, 3000000000u);
  const Problem p = readFails(write("huge_list.ply", bytes));
  EXPECT_EQ(p.where, "element face 0");
  EXPECT_NE(p.what.find("runs past the end"), std::string::npos) << p.what;
}

TEST_F(MeshIoTest, TruncatedAndCorruptedBinaryPlyNeverCrash) {
  const fs::path good = dir_ / "good.ply";
  Eigen::VectorXd field = Eigen::VectorXd::LinSpaced(4, 0.0, 1.0);
  writePly(good, squareVertices(), squareFaces(), {{"f", field}});
  const std::string bytes = read(good);
  for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
    Diagnostics diagnostics;
    EXPECT_FALSE(readFresh(".ply", bytes.substr(0, cut), diagnostics)) << "cut at " << cut;
    EXPECT_FALSE(diagnostics.ok());
  }
  expectCorruptedCopiesReadConsistently(".ply", bytes, 12345, 4);
}

// CGAL reads the counts the header declares and stops: a header counting fewer faces than
// the file holds lost the rest without a word, and bytes after the last element (a second
// mesh pasted in) were ignored.
TEST_F(MeshIoTest, PlyDataBeyondTheHeaderCountsIsRefused) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  const std::string body = std::string(kQuadPositions) + "3 0 1 2\n";
  const Problem extra_faces = readFails(write("few.ply", header + body + "3 0 2 3\n3 1 2 3\n"));
  EXPECT_EQ(extra_faces.where, "line 15");
  EXPECT_EQ(extra_faces.what,
            "the header declares 4 vertices and 1 face, but 2 more lines follow: the header's "
            "element counts must match the data");
  const Problem same_line =
      readFails(write("extra.ply", header + body.substr(0, body.size() - 1) + " 7\nstray\n"));
  EXPECT_EQ(same_line.where, "line 14");
  EXPECT_NE(same_line.what.find("but more values follow on this line and on 1 more line"),
            std::string::npos)
      << same_line.what;

  // Binary: writePly's square with one face fewer declared, and with bytes appended.
  const fs::path good = dir_ / "good.ply";
  writePly(good, squareVertices(), squareFaces());
  const std::string bytes = read(good);
  std::string fewer = bytes;
  fewer.replace(fewer.find("element face 2"), 14, "element face 1");
  const Problem binary_faces = readFails(write("fewer.ply", fewer));
  EXPECT_EQ(binary_faces.where, "byte " + std::to_string(bytes.size() - 13));
  EXPECT_EQ(binary_faces.what,
            "the header declares 4 vertices and 1 face, but 13 more bytes follow the last one: "
            "the header's element counts must match the data");
  const Problem appended = readFails(write("appended.ply", bytes + bytes));
  EXPECT_NE(appended.what.find("but " + std::to_string(bytes.size()) + " more bytes follow"),
            std::string::npos)
      << appended.what;
}

TEST_F(MeshIoTest, PlyEndingInWhitespaceStillReads) {
  const std::string ascii =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" +
      std::string(kQuadPositions) + "4 0 1 2 3";
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  for (const char* tail : {"", "\n", "\r\n", "\n\n  \t\n"}) {
    readOk(write("ascii.ply", ascii + tail), V, F);
    EXPECT_EQ(F, squareFaces()) << "tail '" << tail << "'";
  }
  const fs::path good = dir_ / "good.ply";
  writePly(good, squareVertices(), squareFaces());
  readOk(write("newline.ply", read(good) + "\n"), V, F);
  EXPECT_EQ(F, squareFaces());
}

// --- OBJ, OFF -------------------------------------------------------------------------

TEST_F(MeshIoTest, ObjQuadWithNormalsTexturesAndPolylinesReadsAsTwoTriangles) {
  const fs::path path = write("quad.obj", std::string("# made by hand\no quad\n") +
                                              "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                              "vt 0 0\nvn 0 0 1\n"
                                              "f 1/1/1 2/1/1 3/1/1 4/1/1\n"
                                              "l 1 3\n");
  expectReadsAsTheQuad(path);
}

TEST_F(MeshIoTest, ObjWithoutFacesSaysSo) {
  EXPECT_EQ(readFails(write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n")).what,
            "no faces (no 'f' line)");
  EXPECT_EQ(readFails(write("blank.obj", "# nothing\n")).what,
            "no vertices and no faces (no 'v' or 'f' line: is this an OBJ file?)");
}

// The format separates words by blanks; CGAL alone read "f\t1\t2\t3" as a one-corner face.
TEST_F(MeshIoTest, ObjWithTabSeparatedWordsReadsLikeSpaces) {
  const fs::path path = write("tabs.obj",
                              "v\t0\t0\t0\nv\t1 0\t0\nv 1\t1\t0\nv\t0\t1\t0\n"
                              "f\t1/1/1\t2/1/1\t3/1/1\t4/1/1\n");
  expectReadsAsTheQuad(path);
}

// CGAL let an index one past the end through (its check is "max index > #points"), read 0 as
// that same index, and refused anything farther with a bare "could not parse".
TEST_F(MeshIoTest, ObjIndexOutOfRangeIsRefusedNamingTheLineFaceAndRange) {
  const std::string square = "v 0 0 0\nv 1 0 0\nv 0 1 0\n# a comment\nf 1 2 3\n";
  const Problem past = readFails(write("one_past.obj", square + "f 1 3 4\n"));
  EXPECT_EQ(past.where, "line 6");
  EXPECT_EQ(past.what,
            "face 1: vertex index 4 is out of range: the file has 3 vertices (1 to 3, or -1 to -3 "
            "counting back)");
  EXPECT_EQ(readFails(write("far_past.obj", square + "f 1/1/1 2/1/1 999/1/1\n")).what,
            "face 1: vertex index 999 is out of range: the file has 3 vertices (1 to 3, or -1 to "
            "-3 counting back)");
  EXPECT_EQ(readFails(write("zero.obj", square + "f 0 1 2\n")).what,
            "face 1: vertex index 0: OBJ numbers vertices from 1 (here 1 to 3, or -1 to -3 "
            "counting back)");
  // Counting back is relative to the vertices defined before the face, not to the file's.
  const Problem back = readFails(write("back.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n"));
  EXPECT_EQ(back.where, "line 3");
  EXPECT_EQ(back.what,
            "face 0: vertex index -3 counts back past the first vertex: 2 vertices precede this "
            "line (1 to 3, or -1 to -2 counting back)");
  // A face before any vertex: no range counting back (it read "-1 to -0").
  EXPECT_EQ(readFails(write("first.obj", "f -1 -2 -3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n")).what,
            "face 0: vertex index -1 counts back past the first vertex: 0 vertices precede this "
            "line (1 to 3, and none counting back: no vertex precedes this line)");
}

TEST_F(MeshIoTest, ObjNegativeIndicesCountBackFromTheLatestVertex) {
  expectReadsAsTheQuad(
      write("relative.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf -3 -2 -1\nv 0 1 0\nf 1 -2 -1\n"));
}

// A face with fewer than 3 corners used to be dropped, leaving a hole in a mesh that then
// validated; so did an OBJ face whose index CGAL could not read as an int (the list ended
// at 1 corner).
TEST_F(MeshIoTest, AFaceWithFewerThanThreeCornersIsReportedNotDropped) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
      "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n";
  for (const auto& [face, corners] :
       {std::pair{"2 0 2\n", "has 2 corners"}, std::pair{"1 3\n", "has 1 corner;"},
        std::pair{"0\n", "has 0 corners"}}) {
    const Problem p = readFails(write("short.ply", header + face));
    EXPECT_EQ(p.where, "face 1") << face;
    EXPECT_NE(p.what.find(corners), std::string::npos) << p.what;
    EXPECT_NE(p.what.find("a face needs at least 3"), std::string::npos) << p.what;
  }
  const Problem p =
      readFails(write("big_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2147483648 3\n"));
  EXPECT_EQ(p.where, "face 1");
  EXPECT_NE(p.what.find("has 1 corner; a face needs at least 3"), std::string::npos) << p.what;
  EXPECT_NE(p.what.find("not a number in int range"), std::string::npos) << p.what;
}

// CGAL says only that it failed; the message used to stop there.
TEST_F(MeshIoTest, AnAsciiPlyCgalCannotParseGetsAHintWhereToLook) {
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
      "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  for (const std::string& body : {std::string("0 0 0\n1e400 0 0\n0 1 0\n3 0 1 2\n"),
                                  std::string("0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n")}) {
    const Problem p = readFails(write("bad_token.ply", header + body));
    EXPECT_NE(p.what.find("CGAL could not parse the file (ASCII PLY: check that the header's "
                          "element counts match the lines and that every value is a number"),
              std::string::npos)
        << p.what;
  }
}

TEST_F(MeshIoTest, ObjGarbageAndNanAreReported) {
  readFails(write("garbage.obj", "this is not\nan obj file\n"));
  const Problem p = readFails(write("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_NE(p.what.find("non-finite"), std::string::npos) << p.what;
}

TEST_F(MeshIoTest, OffQuadIsFanTriangulated) {
  expectReadsAsTheQuad(
      write("quad.off", std::string("OFF\n4 1 0\n") + kQuadPositions + "4 0 1 2 3\n"));
}

TEST_F(MeshIoTest, OffDataBeyondTheHeaderCountsIsRefused) {
  const std::string off = std::string("OFF\n4 1 0\n") + kQuadPositions + "3 0 1 2\n";
  const Problem p = readFails(write("few.off", off + "3 0 2 3\n"));
  EXPECT_EQ(p.where, "line 8");
  EXPECT_EQ(p.what,
            "the header declares 4 vertices and 1 face, but 1 more line follows: the header's "
            "counts must match the data");
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(write("comment.off", off + "\n# the end\n\n"), V, F);
  EXPECT_EQ(F.rows(), 1);
}

// CGAL refused these with a bare "could not parse".
TEST_F(MeshIoTest, OffIndexOutOfRangeIsRefusedNamingTheLineFaceAndRange) {
  const std::string off = std::string("OFF\n4 2 0\n") + kQuadPositions + "3 0 1 2\n";
  for (const char* index : {"4", "-1", "99999999999"}) {
    const Problem p = readFails(write("range.off", off + "3 0 2 " + index + "\n"));
    EXPECT_EQ(p.where, "line 8");
    EXPECT_EQ(p.what, "face 1: vertex index " + std::string(index) +
                          " is out of range: the header declares 4 vertices, numbered 0 to 3");
  }
}

TEST_F(MeshIoTest, OffCountsThatCgalWouldAllocateBlindlyAreRefused) {
  EXPECT_EQ(readFails(write("huge.off", "OFF\n900000000 900000000 0\n0 0 0\n")).where, "header");
  const Problem corners =
      readFails(write("corners.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n999999999 0 1 2\n"));
  EXPECT_EQ(corners.where, "line 6");
  EXPECT_NE(readFails(write("binary.off", "OFF BINARY\n")).what.find("binary OFF"),
            std::string::npos);
}

// --- STL --------------------------------------------------------------------------------

TEST_F(MeshIoTest, AsciiStlIsWeldedIntoSharedVertices) {
  const fs::path path = write("square.stl",
                              "solid square\n"
                              " facet normal 0 0 1\n  outer loop\n"
                              "   vertex 0 0 0\n   vertex 1 0 0\n   vertex 1 1 0\n"
                              "  endloop\n endfacet\n"
                              " facet normal 0 0 1\n  outer loop\n"
                              "   vertex 0 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n"
                              "  endloop\n endfacet\n"
                              "endsolid square\n");
  expectReadsAsTheQuad(path);
}

TEST_F(MeshIoTest, BinaryStlWhoseHeaderStartsWithSolidIsReadAsBinaryAndWelded) {
  Eigen::Matrix3f a, b;
  a << 0, 0, 0, 1, 0, 0, 1, 1, 0;
  b << 0, 0, 0, 1, 1, 0, 0, 1, 0.1f;
  const fs::path path = write("square_bin.stl", binaryStl("solid exported by a CAD tool", {a, b}));
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(path, V, F);
  ASSERT_EQ(V.rows(), 4);  // 6 corners, 2 shared
  ASSERT_EQ(F.rows(), 2);
  EXPECT_EQ(F(0, 0), F(1, 0));
  EXPECT_EQ(F(0, 2), F(1, 1));
  EXPECT_NEAR(V(F(1, 2), 2), 0.1, kFloatTolerance);
}

TEST_F(MeshIoTest, BinaryStlWithNanIsRefusedBeforeWeldingCanHideIt) {
  Eigen::Matrix3f a, b;
  a << 0, 0, 0, 1, 0, 0, 1, 1, 0;
  b << 0, 0, 0, 1, 1, 0, std::nanf(""), 1, 0;
  const Problem p = readFails(write("nan.stl", binaryStl("binary", {a, b})));
  EXPECT_EQ(p.where, "facet 1");
}

// What CGAL reads stays readable beside the check for a binary file cut short: an ASCII file
// with blanks before "solid", a binary file with bytes after its facets.
TEST_F(MeshIoTest, AsciiStlAfterBlanksAndBinaryStlWithTrailingBytesAreRead) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(write("lead.stl",
               "\n  solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0 0\n vertex 1 0 0\n"
               " vertex 0 1 0\n endloop\n endfacet\nendsolid x\n"),
         V, F);
  EXPECT_EQ(F.rows(), 1);
  Eigen::Matrix3f a;
  a << 0, 0, 0, 1, 0, 0, 0, 1, 0;
  readOk(write("extra.stl", binaryStl("binary", {a}) + "trailing bytes"), V, F);
  EXPECT_EQ(F.rows(), 1);
  // Zeros padding the file to a block: a whole facet's worth, but no facet.
  readOk(write("padded.stl", binaryStl("binary", {a}) + std::string(100, '\0')), V, F);
  EXPECT_EQ(F.rows(), 1);
}

TEST_F(MeshIoTest, TinyOrGarbageStlIsReported) {
  readFails(write("empty.stl", ""));
  readFails(write("tiny.stl", "abc"));
  readFails(write("garbage.stl", std::string(200, '\x7f')));
  readFails(write("unfinished.stl", "solid x\n facet normal 0 0 1\n outer loop\n vertex 0 0"));
  // A binary file cut short, its header starting "solid" or not: said as binary (it read as a
  // bad ASCII 'vertex' line).
  Eigen::Matrix3f a;
  a << 0, 0, 0, 1, 0, 0, 1, 1, 0;
  for (const std::string header : {"solid exported", "binary"}) {
    std::string bytes = binaryStl(header, {a, a});
    bytes.resize(bytes.size() - 20);
    const Problem p = readFails(write("cut.stl", bytes));
    EXPECT_NE(p.what.find("a binary STL of 2 facets (the count at byte 80) has 184 bytes, this "
                          "file 164: cut short"),
              std::string::npos)
        << header << ": " << p.what;
  }
  // A count below the facets the file holds: CGAL read only the counted ones.
  std::string miscounted = binaryStl("binary", {a, a, a});
  miscounted[80] = 2;
  const Problem p = readFails(write("miscounted.stl", miscounted));
  EXPECT_NE(p.what.find("a binary STL of 2 facets (the count at byte 80) has 184 bytes, this "
                        "file 234: it holds 3 facets, the count is wrong"),
            std::string::npos)
      << p.what;
}

// --- legacy VTK -------------------------------------------------------------------------

const char* kVtkClassic =
    "# vtk DataFile Version 3.0\n"
    "quad and triangle\n"
    "ASCII\n"
    "DATASET POLYDATA\n"
    "FIELD FieldData 1\n"
    "TIME 1 1 double\n"
    "0.5\n"
    "POINTS 5 float\n"
    "0 0 0 1 0 0 1 1 0\n"
    "0 1 0 2 2 2\n"
    "VERTICES 1 2\n"
    "1 4\n"
    "LINES 1 3\n"
    "2 0 4\n"
    "POLYGONS 1 5\n"
    "4 0 1 2 3\n"
    "POINT_DATA 5\n"
    "SCALARS s float 1\n"
    "LOOKUP_TABLE default\n"
    "1 2 3 4 5\n";

TEST_F(MeshIoTest, AsciiClassicVtkReadsPolygonsAndSkipsEverythingElse) {
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(write("classic.vtk", kVtkClassic), V, F);
  ASSERT_EQ(V.rows(), 5);
  EXPECT_EQ(V.topRows(4), quadVertices());
  EXPECT_EQ(F, squareFaces());
}

// As in PLY and OBJ: a face of two corners would leave a hole in the leaflet.
TEST_F(MeshIoTest, AVtkPolygonWithFewerThanThreeCornersIsAnError) {
  std::string text = kVtkClassic;
  text.replace(text.find("POLYGONS 1 5\n"), std::string("POLYGONS 1 5\n").size(),
               "POLYGONS 2 8\n2 0 4\n");
  const Problem p = readFails(write("two_corners.vtk", text));
  EXPECT_NE(p.what.find("a polygon with 2 corner(s)"), std::string::npos) << p.what;
}

TEST_F(MeshIoTest, AsciiVtk51OffsetsAndConnectivityAreRead) {
  const std::string text =
      "# vtk DataFile Version 5.1\n"
      "vtk output\n"
      "ASCII\n"
      "DATASET POLYDATA\n"
      "POINTS 4 float\n"
      "0 0 0 1 0 0 1 1 0\n"
      "0 1 0\n"
      "METADATA\n"
      "INFORMATION 0\n"
      "\n"
      "POLYGONS 3 7\n"
      "OFFSETS vtktypeint64\n"
      "0 4 7\n"
      "CONNECTIVITY vtktypeint64\n"
      "0 1 2 3 0 2 1\n"
      "CELL_DATA 2\n";
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(write("v51.vtk", text), V, F);
  EXPECT_EQ(V, quadVertices());
  EXPECT_EQ(F, (Eigen::MatrixXi{{0, 1, 2}, {0, 2, 3}, {0, 2, 1}}));
}

TEST_F(MeshIoTest, AsciiVtkTriangleStripsBecomeConsistentlyOrientedTriangles) {
  const std::string text = std::string("# vtk DataFile Version 3.0\nstrip\nASCII\n") +
                           "DATASET POLYDATA\nPOINTS 4 double\n" + kQuadPositions +
                           "TRIANGLE_STRIPS 1 5\n4 0 1 3 2\n";
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(write("strip.vtk", text), V, F);
  EXPECT_EQ(F, (Eigen::MatrixXi{{0, 1, 3}, {3, 1, 2}}));
}

// Big-endian binary legacy file: classic int32 POLYGONS or 5.1 int64 OFFSETS/CONNECTIVITY.
std::string binaryVtk(bool offsets_layout) {
  std::string out = std::string("# vtk DataFile Version ") + (offsets_layout ? "5.1" : "3.0") +
                    "\nbinary\nBINARY\nDATASET POLYDATA\nPOINTS 4 float\n";
  const float positions[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  for (float p : positions) appendBigEndian<float>(out, p);
  out += "\n";
  if (offsets_layout) {
    out += "POLYGONS 2 4\nOFFSETS vtktypeint64\n";
    for (std::int64_t v : {0, 4}) appendBigEndian<std::int64_t>(out, v);
    out += "\nCONNECTIVITY vtktypeint64\n";
    for (std::int64_t v : {0, 1, 2, 3}) appendBigEndian<std::int64_t>(out, v);
  } else {
    out += "POLYGONS 1 5\n";
    for (std::int32_t v : {4, 0, 1, 2, 3}) appendBigEndian<std::int32_t>(out, v);
  }
  out += "\nPOINT_DATA 4\n";
  return out;
}

TEST_F(MeshIoTest, BinaryVtkClassicAndOffsetsLayoutsAreRead) {
  for (bool offsets_layout : {false, true}) {
    Eigen::MatrixXd V;
    Eigen::MatrixXi F;
    readOk(write("binary.vtk", binaryVtk(offsets_layout)), V, F);
    EXPECT_EQ(V, quadVertices()) << "offsets layout: " << offsets_layout;
    EXPECT_EQ(F, squareFaces()) << "offsets layout: " << offsets_layout;
  }
}

TEST_F(MeshIoTest, AsciiVtkKeepsNanAndInfinityForTheValidator) {
  const std::string text =
      "# vtk DataFile Version 3.0\nnan\nASCII\nDATASET POLYDATA\nPOINTS 3 double\n"
      "0 0 0\nnan 0 0\n0 -inf 0\nPOLYGONS 1 4\n3 0 1 2\n";
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(write("nan.vtk", text), V, F);
  EXPECT_TRUE(std::isnan(V(1, 0)));
  EXPECT_EQ(V(2, 1), -std::numeric_limits<double>::infinity());
}

TEST_F(MeshIoTest, WriteVtkReadsBackExactlyAndNamesItsScalars) {
  const fs::path path = dir_ / "square.vtk";
  Eigen::VectorXd deviation(4);
  deviation << 0.5, std::nan(""), -1.25, 3.0;
  writeVtk(path, squareVertices(), squareFaces(),
           {{"deviation mm", deviation}, {"leaflet", Eigen::VectorXd::Zero(4)}});
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  readOk(path, V, F);
  EXPECT_TRUE(V.cwiseEqual(squareVertices()).all()) << V;
  EXPECT_EQ(F, squareFaces());
  const std::string text = read(path);
  EXPECT_EQ(text.rfind("# vtk DataFile Version 3.0\nchordfit mesh\nBINARY\n", 0), 0u);
  const std::string point_data = text.substr(text.find("POINT_DATA 4\n"));
  const std::string header = "SCALARS deviation_mm float 1\nLOOKUP_TABLE default\n";
  const std::size_t at = point_data.find(header);
  ASSERT_NE(at, std::string::npos);
  EXPECT_NE(point_data.find("SCALARS leaflet float 1\n"), std::string::npos);
  // Big-endian floats: 0.5, NaN (binary, since VTK 9.1's ASCII reader cannot read "nan"),
  // -1.25, 3.
  float values[4];
  for (int i = 0; i < 4; ++i) {
    std::uint32_t bits = 0;
    for (int b = 0; b < 4; ++b)
      bits = (bits << 8) | static_cast<unsigned char>(point_data[at + header.size() + 4 * i + b]);
    std::memcpy(&values[i], &bits, sizeof bits);
  }
  EXPECT_EQ(values[0], 0.5f);
  EXPECT_TRUE(std::isnan(values[1]));
  EXPECT_EQ(values[2], -1.25f);
  EXPECT_EQ(values[3], 3.0f);
}

TEST_F(MeshIoTest, MalformedVtkIsReportedWithALine) {
  const std::string head = "# vtk DataFile Version 3.0\nt\nASCII\nDATASET POLYDATA\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"hello\n", "line 1"},
      {"# vtk DataFile Version 3.0\nt\nTEXT\n", "line 3"},
      {"# vtk DataFile Version 3.0\nt\nASCII\nDATASET UNSTRUCTURED_GRID\n", "line 4"},
      {head + "POINTS 3 float\n0 0 0\n1 0 zero\n0 1 0\n", "line 7"},
      {head + "POINTS 99999999999 float\n0 0 0\n", "line 5"},
      {head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 9\n3 0 1 2\n", "line 7"},
      {head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n5 0 1 2\n", "line 7"},
      {head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nBANANAS 3\n", "line 7"},
      {head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\n", "line"},  // no polygons
      {head + "POINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 3 3\nOFFSETS vtktypeint64\n0 5 3\n"
              "CONNECTIVITY vtktypeint64\n0 1 2\n",
       "line 7"},
  };
  for (const auto& [text, where] : cases) {
    const Problem p = readFails(write("bad.vtk", text));
    EXPECT_EQ(p.where.rfind(where, 0), 0u) << "got '" << p.where << ": " << p.what << "' for:\n"
                                           << text;
  }
}

TEST_F(MeshIoTest, TruncatedAndCorruptedVtkNeverCrash) {
  for (const std::string& bytes : {std::string(kVtkClassic), binaryVtk(false), binaryVtk(true)}) {
    for (std::size_t cut = 0; cut < bytes.size(); ++cut) {
      Diagnostics diagnostics;
      const bool ok = readFresh(".vtk", bytes.substr(0, cut), diagnostics);
      EXPECT_EQ(ok, diagnostics.ok()) << "cut at " << cut;
    }
    expectCorruptedCopiesReadConsistently(".vtk", bytes, 777, 3);
  }
}

TEST_F(MeshIoTest, HugeBinaryVtkCountIsRefusedWithoutAllocating) {
  std::string bytes = "# vtk DataFile Version 3.0\nt\nBINARY\nDATASET POLYDATA\nPOINTS 3 float\n";
  for (int k = 0; k < 9; ++k) appendBigEndian<float>(bytes, 0.0f);
  bytes += "\nPOLYGONS 1 4000000000\n";
  const Problem p = readFails(write("huge.vtk", bytes));
  EXPECT_NE(p.what.find("do not fit"), std::string::npos) << p.what;
}

// --- dispatch and writer contracts --------------------------------------------------------

TEST_F(MeshIoTest, MissingFileIsReportedAsNotFound) {
  Diagnostics diagnostics;
  Eigen::MatrixXd V;
  Eigen::MatrixXi F;
  EXPECT_FALSE(readMesh(dir_ / "absent.ply", V, F, diagnostics, "valve.ply"));
  ASSERT_EQ(diagnostics.problems().size(), 1u);
  EXPECT_EQ(diagnostics.problems()[0].file, "valve.ply");
  EXPECT_EQ(diagnostics.problems()[0].what, "file not found");
}

TEST_F(MeshIoTest, UnknownExtensionIsNamedInTheMessage) {
  const Problem p = readFails(write("mesh.xyz", "0 0 0\n"));
  EXPECT_NE(p.what.find(".xyz"), std::string::npos) << p.what;
}

TEST_F(MeshIoTest, WritersRefuseWrongExtensionsAndMismatchedFields) {
  EXPECT_THROW(writePly(dir_ / "mesh.vtk", squareVertices(), squareFaces()), std::runtime_error);
  EXPECT_THROW(writeVtk(dir_ / "mesh.ply", squareVertices(), squareFaces()), std::runtime_error);
  EXPECT_THROW(writePly(dir_ / "mesh.ply", squareVertices(), squareFaces(),
                        {{"short", Eigen::VectorXd::Zero(3)}}),
               std::invalid_argument);
  EXPECT_FALSE(fs::exists(dir_ / "mesh.ply"));
}

}  // namespace
}  // namespace chordfit
