// Tests for the cloud readers (PLY, PCD, text, OFF/OBJ/STL), read_cloud and the io.read_cloud node.
#include "nodes/io/read_cloud.h"

#include <gtest/gtest.h>
#include <liblzf/lzf.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "engine/file_ref.h"
#include "engine/node.h"
#include "nodes/io/mesh_reader.h"
#include "nodes/io/mm_units.h"
#include "nodes/io/pcd_reader.h"
#include "nodes/io/ply_reader.h"
#include "nodes/types/ply_writer.h"
#include "nodes/io/text_cloud_reader.h"
#include "tests/nodes/io/bytes.h"

namespace scallop {
namespace io_nodes {
NodeDecl make_read_cloud_node();
}  // namespace io_nodes
using io_nodes::make_read_cloud_node;
}

namespace scallop {
namespace {

namespace fs = std::filesystem;
using V = Eigen::Vector3d;

// A fresh directory per test, removed afterwards.
class ReadCloud : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    dir_ = fs::temp_directory_path() / ("scallop_io_read_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // Writes `bytes` to dir/name and returns the path.
  std::string file(const std::string& name, const std::string& bytes) {
    const std::string p = (dir_ / name).string();
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

// The message read_cloud throws for `path`, or "<no error>".
std::string error_of(const std::string& path) {
  try {
    read_cloud(path);
  } catch (const CloudReadError& e) {
    return e.what();
  }
  return "<no error>";
}

using test::be;
using test::le;

bool same(double a, double b) { return (std::isnan(a) && std::isnan(b)) || std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

void expect_points(const PointCloud& c, const std::vector<V>& want) {
  ASSERT_EQ(c.points.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(same(c.points[i][k], want[i][k])) << "point " << i << " coord " << k << ": " << c.points[i][k] << " vs " << want[i][k];
}

void expect_normals(const PointCloud& c, const std::vector<V>& want) {
  ASSERT_TRUE(c.has_normals());
  ASSERT_EQ(c.normals.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i)
    for (int k = 0; k < 3; ++k) EXPECT_TRUE(same(c.normals[i][k], want[i][k])) << "normal " << i << " coord " << k;
}

const std::vector<V> kAwkward = {V(0.1, -0.0, 1e-300), V(std::numbers::pi, -1e300, 123456789.123456789),
                                 V(std::numeric_limits<double>::quiet_NaN(), 5e-324, -2.5)};
const std::vector<V> kNormals = {V(0, 0, 1), V(0.6, 0.8, 0), V(-1.0 / 3, 2.0 / 3, -2.0 / 3)};

// ---------------------------------------------------------------- PLY

TEST_F(ReadCloud, PlyBinaryRoundTripIsExact) {
  PointCloud c;
  c.points = kAwkward;
  write_ply(path("a.ply"), c);
  PointCloud r = read_cloud(path("a.ply"));
  expect_points(r, kAwkward);
  EXPECT_FALSE(r.has_normals());
  c.normals = kNormals;
  write_ply(path("b.ply"), c, true);
  r = read_cloud(path("b.ply"));
  expect_points(r, kAwkward);
  expect_normals(r, kNormals);
}

TEST_F(ReadCloud, PlyAsciiRoundTripIsExact) {
  PointCloud c;
  c.points = kAwkward;
  c.normals = kNormals;
  write_ply(path("a.ply"), c, false);
  PointCloud r = read_cloud(path("a.ply"));
  expect_points(r, kAwkward);
  expect_normals(r, kNormals);
}

TEST_F(ReadCloud, PlyBigEndianFloatWithFaceBeforeVertices) {
  std::string s =
      "ply\nformat binary_big_endian 1.0\ncomment made by hand\n"
      "element face 2\nproperty list uchar int vertex_indices\nproperty uchar flags\n"
      "element vertex 2\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\n"
      "end_header\n";
  s += be<std::uint8_t>(3) + be<std::int32_t>(0) + be<std::int32_t>(1) + be<std::int32_t>(1) + be<std::uint8_t>(7);
  s += be<std::uint8_t>(0) + be<std::uint8_t>(7);  // an empty list
  s += be(1.5f) + be(-2.25f) + be(1e-3f) + be<std::uint8_t>(255);
  s += be(-0.0f) + be(4096.0f) + be(3.0f) + be<std::uint8_t>(0);
  PointCloud r = read_ply(file("be.ply", s));
  expect_points(r, {V(1.5, -2.25, double(1e-3f)), V(-0.0, 4096, 3)});
  EXPECT_FALSE(r.has_normals());
}

TEST_F(ReadCloud, PlyAnyScalarTypeAndNormals) {
  std::string s =
      "ply\nformat binary_little_endian 1.0\n"
      "element vertex 1\nproperty int8 x\nproperty ushort y\nproperty int32 z\n"
      "property float64 nx\nproperty float32 ny\nproperty char nz\nproperty uint confidence\n"
      "end_header\n";
  s += le<std::int8_t>(-5) + le<std::uint16_t>(60000) + le<std::int32_t>(-100000) + le(0.25) + le(0.5f) +
       le<std::int8_t>(-1) + le<std::uint32_t>(4000000000u);
  PointCloud r = read_ply(file("t.ply", s));
  expect_points(r, {V(-5, 60000, -100000)});
  expect_normals(r, {V(0.25, 0.5, -1)});
}

TEST_F(ReadCloud, PlyAsciiWithObjInfoAndRangeGridAfterVertices) {
  const std::string s =
      "ply\nformat ascii 1.0\nobj_info is_cyberware_data 1\nobj_info num_cols 2\n"
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element range_grid 4\nproperty list uchar int vertex_indices\nend_header\n"
      "1 2 3\n-4.5 5e-1 +6\n7 8 9\n1 0\n0\n1 1\n1 2\n";
  PointCloud r = read_cloud(file("r.ply", s));
  expect_points(r, {V(1, 2, 3), V(-4.5, 0.5, 6), V(7, 8, 9)});
}

TEST_F(ReadCloud, PlyCrLfHeaderAndZeroVertices) {
  PointCloud r = read_cloud(file("z.ply", "ply\r\nformat ascii 1.0\r\nelement vertex 0\r\nproperty float x\r\n"
                                          "property float y\r\nproperty float z\r\nend_header\r\n"));
  EXPECT_EQ(r.size(), 0u);
  PointCloud empty;
  write_ply(path("e.ply"), empty);
  EXPECT_EQ(read_cloud(path("e.ply")).size(), 0u);
}

TEST_F(ReadCloud, PlyMalformed) {
  const std::string head3 = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  std::string p = file("bad.ply", head3 + "1 2 3\n4 5\n7 8 9\n");
  EXPECT_EQ(error_of(p), p + ": line 9: expected 3 values for vertex 1, found 2");
  p = file("bad.ply", head3 + "1 2 3\n4 5 6 7\n7 8 9\n");
  EXPECT_EQ(error_of(p), p + ": line 9: expected 3 values for vertex 1, found 4");
  p = file("bad.ply", head3 + "1 2 3\n4 5 6\n7 eight 9\n");
  EXPECT_EQ(error_of(p), p + ": line 10: bad value 'eight' for property 'y' of vertex 2");
  p = file("bad.ply", head3 + "1 2 3\n4 5 6\n");
  EXPECT_EQ(error_of(p), p + ": line 10: file ends before vertex 2 of 3");
  p = file("bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 1\nproperty list uchar int vertex_indices\nend_header\n1 2 3\n3 0 0\n");
  EXPECT_EQ(error_of(p), p + ": line 11: expected 4 values for face 0, found 3");
  p = file("bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 1\nproperty list uchar int vertex_indices\nend_header\n1 2 3\n-1\n");
  EXPECT_EQ(error_of(p), p + ": line 11: bad list length '-1' for property 'vertex_indices' of face 0");

  p = file("bad.ply", "plyx\n");
  EXPECT_EQ(error_of(p), p + ": line 1: not a PLY file (the first line must be 'ply')");
  p = file("bad.ply", "ply\nelement vertex 1\nproperty float x\nend_header\n");
  EXPECT_EQ(error_of(p), p + ": line 4: header has no 'format' line");
  p = file("bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
  EXPECT_EQ(error_of(p), p + ": line 4: header ends without 'end_header'");
  p = file("bad.ply", "ply\nformat ascii 1.0\nelement face 1\nend_header\n");
  EXPECT_EQ(error_of(p), p + ": line 4: header has no 'element vertex'");
  p = file("bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n");
  EXPECT_EQ(error_of(p), p + ": line 6: vertex element has no 'z' property");
  p = file("bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\n");
  EXPECT_EQ(error_of(p), p + ": line 4: unknown property type 'real'");
  p = file("bad.ply", "ply\nformat ascii 1.0\nproperty float x\n");
  EXPECT_EQ(error_of(p), p + ": line 3: property before any element");
  p = file("bad.ply", "ply\nformat binary_middle_endian 1.0\n");
  EXPECT_EQ(error_of(p), p + ": line 2: unknown format 'binary_middle_endian' (expected ascii, binary_little_endian or binary_big_endian)");
  p = file("bad.ply", "ply\nformat ascii 1.0\nelement vertex many\n");
  EXPECT_EQ(error_of(p), p + ": line 3: bad count 'many' for element 'vertex'");
  p = file("bad.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\n");
  EXPECT_EQ(error_of(p), p + ": line 4: list length type 'float' is not an integer type");
  p = file("bad.ply", "ply\nformat ascii 1.0\nvertices 3\n");
  EXPECT_EQ(error_of(p), p + ": line 3: unknown header line starting with 'vertices'");
}

TEST_F(ReadCloud, PlyBinaryMalformedNeverReadsPastTheEnd) {
  // 100 vertices declared, 12 and a half present: the message names the cut vertex's first byte.
  const std::string head =
      "ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  std::string s = head;
  for (int i = 0; i < 12 * 3 + 2; ++i) s += le(float(i));
  std::string p = file("bad.ply", s);
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(head.size() + 12 * 12) + ": file ends inside vertex 12 of 100");

  // A lying count of 10^18 must fail cleanly, not allocate.
  s = "ply\nformat binary_little_endian 1.0\nelement vertex 1000000000000000000\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
  const std::size_t at = s.size();
  s += le(1.0) + le(2.0) + le(3.0) + le(4.0);
  p = file("bad.ply", s);
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(at + 24) + ": file ends inside vertex 1 of 1000000000000000000");

  // A skipped element before the vertices that is cut short.
  s = "ply\nformat binary_little_endian 1.0\nelement junk 5\nproperty int a\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  const std::size_t j = s.size();
  s += le<std::int32_t>(1) + le<std::int32_t>(2) + "ab";
  p = file("bad.ply", s);
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(j + 8) + ": file ends inside junk 2 of 5");

  // A list longer than the file, and a negative list length.
  s = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list int int vertex_indices\nend_header\n";
  const std::size_t f = s.size() + 12;
  s += le(1.f) + le(2.f) + le(3.f);
  p = file("bad.ply", s + le<std::int32_t>(2000000000) + le<std::int32_t>(0));
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(f) + ": file ends inside face 0 of 1");
  p = file("bad.ply", s + le<std::int32_t>(-3));
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(f) + ": negative list length -3 in property 'vertex_indices' of face 0");
}

TEST_F(ReadCloud, PlyDataPastTheLastDeclaredElementIsAnError) {
  // 5000 points written, the header's count lowered to 2500: the other half must not vanish.
  PointCloud c;
  for (int i = 0; i < 5000; ++i) c.points.emplace_back(i, 0.5 * i, 1.0);
  auto lower_count = [&](const std::string& name, bool binary) {
    write_ply(path(name), c, binary);
    std::ifstream in(path(name), std::ios::binary);
    std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::size_t at = s.find("element vertex 5000\n");
    EXPECT_NE(at, std::string::npos);
    s.replace(at, 19, "element vertex 2500");
    return std::make_pair(file(name, s), s);
  };
  auto [p, s] = lower_count("half.ply", true);
  const std::size_t data = s.find("end_header\n") + 11;
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(data + 2500 * 24) +
                             ": 60000 bytes after the last declared element 'vertex' (2500 declared): the header's "
                             "count is smaller than the data");
  std::tie(p, s) = lower_count("half_ascii.ply", false);
  const auto header_lines = std::count(s.begin(), s.begin() + s.find("end_header\n") + 11, '\n');
  EXPECT_EQ(error_of(p), p + ": line " + std::to_string(header_lines + 2500 + 1) +
                             ": 2500 lines after the last declared element 'vertex' (2500 declared): the header's "
                             "count is smaller than the data");

  // the last element need not be the vertices; one stray line is named too; blank lines may follow
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                           "element face 1\nproperty list uchar int vertex_indices\nend_header\n1 2 3\n1 0\n";
  p = file("face.ply", head + "\n7 8 9\n\n");
  EXPECT_EQ(error_of(p), p + ": line 13: 1 line after the last declared element 'face' (1 declared): the header's "
                             "count is smaller than the data");
  expect_points(read_cloud(file("blank.ply", head + "\n  \r\n\n")), {V(1, 2, 3)});
}

// ---------------------------------------------------------------- PCD

TEST_F(ReadCloud, PcdAsciiWithNormalsAndExtraFields) {
  const std::string s =
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n"
      "FIELDS x y z intensity normal_x normal_y normal_z curvature\nSIZE 4 4 4 4 4 4 4 4\n"
      "TYPE F F F F F F F F\nCOUNT 1 1 1 1 1 1 1 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n"
      "1 2 3 9 0 0 1 0\n-1.5 0.25 1e2 9 0.6 0.8 0 0\nnan nan nan 0 nan nan nan 0\n";
  PointCloud r = read_cloud(file("a.pcd", s));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_points(r, {V(1, 2, 3), V(-1.5, 0.25, 100), V(nan, nan, nan)});
  expect_normals(r, {V(0, 0, 1), V(0.6, 0.8, 0), V(nan, nan, nan)});
}

TEST_F(ReadCloud, PcdBinaryMixedTypesV06Header) {
  // No VERSION, COUNT or POINTS: v0.6-like, POINTS = WIDTH * HEIGHT. rgb is a 4-byte unsigned.
  std::string s = "FIELDS x y z rgb _\nSIZE 8 4 2 4 1\nTYPE F F I U U\nWIDTH 1\nHEIGHT 2\nDATA binary\n";
  s += le(0.1) + le(2.5f) + le<std::int16_t>(-7) + le<std::uint32_t>(0xff00ff) + "\x01";
  s += le(-3.0) + le(1e-3f) + le<std::int16_t>(32767) + le<std::uint32_t>(0) + "\x02";
  PointCloud r = read_cloud(file("b.pcd", s));
  expect_points(r, {V(0.1, 2.5, -7), V(-3, double(1e-3f), 32767)});
  EXPECT_FALSE(r.has_normals());
}

// A binary_compressed PCD of fields x y z intensity normal_x normal_y normal_z, all float, made
// the way PCL makes it: structure of arrays, LZF-compressed.
std::string compressed_pcd(const std::vector<V>& p, const std::vector<V>& n) {
  std::string soa;
  for (int k = 0; k < 3; ++k)
    for (const V& v : p) soa += le(float(v[k]));
  for (std::size_t i = 0; i < p.size(); ++i) soa += le(float(i));
  for (int k = 0; k < 3; ++k)
    for (const V& v : n) soa += le(float(v[k]));
  std::string out(soa.size() + soa.size() / 16 + 64, '\0');
  const unsigned c = lzf_compress(soa.data(), soa.size(), out.data(), out.size());
  EXPECT_GT(c, 0u);
  out.resize(c);
  return "VERSION 0.7\nFIELDS x y z intensity normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4 4\nTYPE F F F F F F F\n"
         "COUNT 1 1 1 1 1 1 1\nWIDTH " + std::to_string(p.size()) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
         std::to_string(p.size()) + "\nDATA binary_compressed\n" + le<std::uint32_t>(c) +
         le<std::uint32_t>(static_cast<std::uint32_t>(soa.size())) + out;
}

TEST_F(ReadCloud, PcdBinaryCompressed) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<V> p, n;
  for (int i = 0; i < 500; ++i) {
    p.emplace_back(i * 0.5, -i, i % 7 == 0 ? nan : 0.25 * (i % 4));
    n.emplace_back(0, i % 2, 1 - i % 2);
  }
  PointCloud r = read_cloud(file("c.pcd", compressed_pcd(p, n)));
  expect_points(r, p);
  expect_normals(r, n);
}

TEST_F(ReadCloud, PcdMalformed) {
  const std::string head = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 100\nHEIGHT 1\nPOINTS 100\n";
  std::string p = file("bad.pcd", head + "DATA ascii\n1 2 3\n4 5\n");
  EXPECT_EQ(error_of(p), p + ": line 11: expected 3 values for point 1, found 2");
  p = file("bad.pcd", head + "DATA ascii\n1 2 3\n4 5 x\n");
  EXPECT_EQ(error_of(p), p + ": line 11: bad value 'x' for field 'z' of point 1");
  p = file("bad.pcd", head + "DATA ascii\n1 2 3\n");
  EXPECT_EQ(error_of(p), p + ": line 11: file ends before point 1 of 100");
  std::string s = head + "DATA binary\n";
  const std::size_t at = s.size();
  p = file("bad.pcd", s + le(1.f) + le(2.f) + le(3.f) + le(4.f));
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(at + 12) + ": file ends inside point 1 of 100");
  const std::string hc = head + "DATA binary_compressed\n";
  const std::size_t c = hc.size();
  p = file("bad.pcd", hc + le<std::uint32_t>(1000) + le<std::uint32_t>(1200) + "abc");
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(c) + ": compressed size 1000 but only 3 bytes follow");
  p = file("bad.pcd", hc + le<std::uint32_t>(3) + le<std::uint32_t>(1000) + "abc");
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(c + 4) + ": uncompressed size 1000 does not match 100 points of 12 bytes");
  p = file("bad.pcd", hc + le<std::uint32_t>(3) + le<std::uint32_t>(1200) + "abc");
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(c + 4) + ": uncompressed size 1200 is impossible for 3 compressed bytes");
  p = file("bad.pcd", hc + le<std::uint32_t>(20) + le<std::uint32_t>(1200) + std::string(20, '\xff'));
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(c + 8) + ": corrupt LZF data");
  p = file("bad.pcd", hc + "abc");
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(c) + ": file ends inside the compressed and uncompressed sizes");

  p = file("bad.pcd", "VERSION 0.7\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n");
  EXPECT_EQ(error_of(p), p + ": line 5: header has no FIELDS line");
  p = file("bad.pcd", "FIELDS x y z\nSIZE 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n");
  EXPECT_EQ(error_of(p), p + ": line 5: SIZE has 2 values but FIELDS has 3");
  p = file("bad.pcd", "FIELDS x y z\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n");
  EXPECT_EQ(error_of(p), p + ": line 4: header has no SIZE line");
  p = file("bad.pcd", "FIELDS x y w\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n");
  EXPECT_EQ(error_of(p), p + ": line 5: FIELDS has no 'z'");
  p = file("bad.pcd", "FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\nPOINTS 1\nDATA ascii\n1 2 3\n");
  EXPECT_EQ(error_of(p), p + ": line 5: field 'z' is F with SIZE 2 (expected 4 or 8)");
  p = file("bad.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\n");
  EXPECT_EQ(error_of(p), p + ": line 4: header ends without a DATA line");
  p = file("bad.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nPOINTS 1\nDATA binary_lz4\n");
  EXPECT_EQ(error_of(p), p + ": line 5: unknown DATA format 'binary_lz4' (expected ascii, binary or binary_compressed)");
  p = file("bad.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nDATA ascii\n");
  EXPECT_EQ(error_of(p), p + ": line 4: header has neither POINTS nor WIDTH");
  p = file("bad.pcd", "ply\n");
  EXPECT_EQ(error_of(p), p + ": line 1: not a PCD file (unknown header line starting with 'ply')");
}

TEST_F(ReadCloud, PcdZeroPoints) {
  EXPECT_EQ(read_cloud(file("z.pcd", "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 0\nHEIGHT 1\nPOINTS 0\nDATA binary\n")).size(), 0u);
}

// ---------------------------------------------------------------- text

TEST_F(ReadCloud, XyzAndCsv) {
  PointCloud r = read_cloud(file("a.xyz", "# scanner output\n1 2 3\n\n4\t5  6   # trailing comment\n-7e-1 8 9\n"));
  expect_points(r, {V(1, 2, 3), V(4, 5, 6), V(-0.7, 8, 9)});
  EXPECT_FALSE(r.has_normals());
  r = read_cloud(file("b.csv", "x,y,z,nx,ny,nz,quality\r\n1,2,3,0,0,1,5\r\n4;5;6;1;0;0;5\r\n"));
  expect_points(r, {V(1, 2, 3), V(4, 5, 6)});
  expect_normals(r, {V(0, 0, 1), V(1, 0, 0)});
  r = read_cloud(file("c.txt", "1, 2, 3, 0.5\n"));  // four columns: x y z and something else
  expect_points(r, {V(1, 2, 3)});
  EXPECT_FALSE(r.has_normals());
  // .pts: a count line, then x y z intensity r g b: no normals.
  r = read_cloud(file("d.pts", "2\n1 2 3 -1200 10 20 30\n4 5 6 7 10 20 30\n"));
  expect_points(r, {V(1, 2, 3), V(4, 5, 6)});
  EXPECT_FALSE(r.has_normals());
  EXPECT_EQ(read_cloud(file("e.csv", "x,y,z\n")).size(), 0u);
}

TEST_F(ReadCloud, TextMalformed) {
  std::string p = file("bad.xyz", "1 2 3\n4 5 six\n");
  EXPECT_EQ(error_of(p), p + ": line 2: bad number 'six' in column 3");
  p = file("bad.csv", "x,y,z\n1,2,3\n4,5\n");
  EXPECT_EQ(error_of(p), p + ": line 3: expected 3 values like the first point, found 2");
  p = file("bad.txt", "# two columns\n1 2\n");
  EXPECT_EQ(error_of(p), p + ": line 2: expected at least 3 values (x y z), found 2");
  p = file("bad.csv", "1,2,3\n4,,5\n");
  EXPECT_EQ(error_of(p), p + ": line 2: empty value in column 2");
  p = file("bad.csv", "1;2;3\n4;5 6;7\n");
  EXPECT_EQ(error_of(p), p + ": line 2: bad number '5 6' in column 2");
}

TEST_F(ReadCloud, TextByteOrderMarkIsSkipped) {
  // the BOM used to make the first point look like a header line, and it was dropped
  expect_points(read_cloud(file("bom.xyz", "\xEF\xBB\xBF" "1 2 3\n4 5 6\n")), {V(1, 2, 3), V(4, 5, 6)});
  expect_points(read_cloud(file("bom.csv", "\xEF\xBB\xBF" "x,y,z\r\n1,2,3\r\n")), {V(1, 2, 3)});
}

TEST_F(ReadCloud, TextDecimalCommasAreNamed) {
  // blank-separated, a later line, and the European CSV form (which split on both separators
  // looked like six good columns)
  for (const auto& [name, text, line] : {std::tuple{"comma.xyz", "1,5 2,0 3,0\n4,5 5,0 6,0\n", 1},
                                         std::tuple{"comma.txt", "1.5 2 3\n4,5\t5,0  6\n", 2},
                                         std::tuple{"comma.csv", "x;y;z\n1,5;2,0;3,0\n", 2}}) {
    const std::string p = file(name, text);
    EXPECT_EQ(error_of(p), p + ": line " + std::to_string(line) + ": decimal commas are not supported; use '.'");
  }
  // commas as separators are still fine, with or without blanks after them
  expect_points(read_cloud(file("ok.csv", "1, 2, 3\n4,5,6\n")), {V(1, 2, 3), V(4, 5, 6)});
}

// ---------------------------------------------------------------- meshes

TEST_F(ReadCloud, OffHeaderAloneOrWithCountsAndMixedFaces) {
  const std::vector<V> want = {V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(0, 1, 0), V(0.5, 0.5, 1)};
  const std::string body = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0.5 0.5 1\n4 0 1 2 3\n3 0 1 4 255 0 0\n3 1 2 4\n3 2 3 4\n3 3 0 4\n";
  expect_points(read_cloud(file("a.off", "OFF\n# a pyramid\n5 5 0\n" + body)), want);
  expect_points(read_cloud(file("b.OFF", "OFF 5 5 8\n" + body)), want);
  PointCloud r = read_cloud(file("c.off", "NOFF\n1 0 0\n1 2 3 0 0 1\n"));
  expect_points(r, {V(1, 2, 3)});
  expect_normals(r, {V(0, 0, 1)});
}

TEST_F(ReadCloud, ObjVertices) {
  PointCloud r = read_cloud(file("a.obj", "# obj\no thing\nv 1 2 3\nvn 0 0 1\nvt 0.5 0.5\nv 4 5 6 1.0\nv 7 8 9 0.1 0.2 0.3\nf 1//1 2//1 3//1\n"));
  expect_points(r, {V(1, 2, 3), V(4, 5, 6), V(7, 8, 9)});
  EXPECT_FALSE(r.has_normals());
}

// Two triangles of a unit square sharing an edge: 6 corners, 4 vertices once welded (-0 == 0).
const char* kSquareAscii =
    "solid square\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 1 1 0\n  endloop\n endfacet\n"
    " facet normal 0 0 1\n  outer loop\n   vertex -0 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid square\n";

std::string square_binary(std::string header) {
  header.resize(80, ' ');
  std::string s = header + le<std::uint32_t>(2);
  const float tri[2][9] = {{0, 0, 0, 1, 0, 0, 1, 1, 0}, {-0.f, 0, 0, 1, 1, 0, 0, 1, 0}};
  for (const auto& t : tri) {
    s += le(0.f) + le(0.f) + le(1.f);
    for (float f : t) s += le(f);
    s += le<std::uint16_t>(0);
  }
  return s;
}

TEST_F(ReadCloud, StlAsciiAndBinaryAreWelded) {
  const std::vector<V> want = {V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(0, 1, 0)};
  expect_points(read_cloud(file("a.stl", kSquareAscii)), want);
  expect_points(read_cloud(file("b.stl", square_binary("binary square"))), want);
  // A binary file whose header starts with "solid", as many exporters write.
  expect_points(read_cloud(file("c.STL", square_binary("solid square, binary"))), want);
}

TEST_F(ReadCloud, MeshMalformed) {
  std::string p = file("bad.off", "OFF\n3 1 0\n0 0 0\n1 0\n");
  EXPECT_EQ(error_of(p), p + ": line 4: expected 3 values for vertex 1, found 2");
  p = file("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n");
  EXPECT_EQ(error_of(p), p + ": line 5: file ends before vertex 2 of 3");
  p = file("bad.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  EXPECT_EQ(error_of(p), p + ": line 6: face 0 has index '3' but there are 3 vertices");
  p = file("bad.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n");
  EXPECT_EQ(error_of(p), p + ": line 6: face 0 has 4 corners but only 3 indices");
  p = file("bad.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(error_of(p), p + ": line 7: file ends before face 1 of 2");
  p = file("bad.off", "OFF\nthree 1\n");
  EXPECT_EQ(error_of(p), p + ": line 2: expected the counts 'vertices faces [edges]'");
  p = file("bad.off", "PLY\n");
  EXPECT_EQ(error_of(p), p + ": line 1: not an OFF file (the first word must be 'OFF')");
  p = file("bad.off", "4OFF\n");
  EXPECT_EQ(error_of(p), p + ": line 1: unsupported OFF variant '4OFF' (expected OFF, COFF, NOFF or CNOFF)");
  p = file("bad.obj", "v 1 2 3\nv 4 5\n");
  EXPECT_EQ(error_of(p), p + ": line 2: expected 'v x y z', found 2 values");
  p = file("bad.obj", "v 1 2 3\nv 4 5 z\n");
  EXPECT_EQ(error_of(p), p + ": line 2: bad number 'z'");
  std::string s = square_binary("cut short");
  p = file("bad.stl", s.substr(0, s.size() - 10));
  EXPECT_EQ(error_of(p), p + ": byte 134: file ends inside triangle 1 of 2");
  p = file("bad.stl", "tiny");
  EXPECT_EQ(error_of(p), p + ": byte 0: file too short for a binary STL header (84 bytes)");
  p = file("bad.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n");
  EXPECT_EQ(error_of(p), p + ": line 6: facet 0 has 2 vertices, expected 3");
  p = file("bad.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n");
  EXPECT_EQ(error_of(p), p + ": line 4: expected 'vertex x y z'");
  p = file("bad.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n");
  EXPECT_EQ(error_of(p), p + ": line 5: file ends inside facet 0");
}

// ---------------------------------------------------------------- issue 11: BOM, trailing data, decimal commas

TEST_F(ReadCloud, PlyByteOrderMarkAndDecimalCommas) {
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                           "end_header\n";
  // the BOM made the magic word wrong: "not a PLY file"
  expect_points(read_cloud(file("bom.ply", "\xEF\xBB\xBF" + head + "1 2 3\n")), {V(1, 2, 3)});
  const std::string p = file("comma.ply", head + "1,5 2 3\n");
  EXPECT_EQ(error_of(p), p + ": line 8: decimal commas are not supported; use '.'");
}

TEST_F(ReadCloud, PcdByteOrderMarkTrailingDataAndDecimalCommas) {
  const std::string head = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n";
  // the BOM made the first line "not a PCD file"
  expect_points(read_cloud(file("bom.pcd", "\xEF\xBB\xBF# .PCD v0.7\n" + head + "DATA ascii\n1 2 3\n4 5 6\n")),
                {V(1, 2, 3), V(4, 5, 6)});
  // POINTS smaller than the data: was read silently, the rest dropped
  std::string p = file("more.pcd", head + "DATA ascii\n1 2 3\n4 5 6\n7 8 9\n\n10 11 12\n");
  EXPECT_EQ(error_of(p), p + ": line 12: 2 lines after the last point (2 declared): the header's POINTS is smaller "
                             "than the data");
  expect_points(read_cloud(file("blank.pcd", head + "DATA ascii\n1 2 3\n4 5 6\n\n \n")), {V(1, 2, 3), V(4, 5, 6)});
  const std::string hb = head + "DATA binary\n";
  std::string s = hb;
  for (float f : {1.f, 2.f, 3.f, 4.f, 5.f, 6.f, 7.f, 8.f, 9.f}) s += le(f);
  p = file("more_binary.pcd", s);
  EXPECT_EQ(error_of(p), p + ": byte " + std::to_string(hb.size() + 24) +
                             ": 12 bytes after the last point (2 declared): the header's POINTS is smaller than the data");
  // binary_compressed: PCL's writer leaves bytes after the block (milk.pcd: 3913); its count is
  // checked against the uncompressed size instead
  expect_points(read_cloud(file("pad.pcd", compressed_pcd({V(1, 2, 3)}, {V(0, 0, 1)}) + std::string(16, '\0'))),
                {V(1, 2, 3)});
  p = file("comma.pcd", head + "DATA ascii\n1 2 3\n4,5 5 6\n");
  EXPECT_EQ(error_of(p), p + ": line 11: decimal commas are not supported; use '.'");
}

TEST_F(ReadCloud, MeshByteOrderMarkTrailingDataAndDecimalCommas) {
  // OFF: the BOM made it "not an OFF file"; counts smaller than the data dropped vertices silently
  expect_points(read_cloud(file("bom.off", "\xEF\xBB\xBFOFF\n1 0 0\n1 2 3\n")), {V(1, 2, 3)});
  std::string p = file("more.off", "OFF\n2 0 0\n1 2 3\n4 5 6\n7 8 9\n10 11 12\n\n");
  EXPECT_EQ(error_of(p), p + ": line 5: 2 lines after the last declared face (2 vertices, 0 faces declared): the "
                             "header's counts are smaller than the data");
  p = file("more_faces.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n");
  EXPECT_EQ(error_of(p), p + ": line 7: 1 line after the last declared face (3 vertices, 1 faces declared): the "
                             "header's counts are smaller than the data");
  expect_points(read_cloud(file("comment.off", "OFF\n1 0 0\n1 2 3\n# end\n\n")), {V(1, 2, 3)});
  p = file("comma.off", "OFF\n1 0 0\n1,5 2 3\n");
  EXPECT_EQ(error_of(p), p + ": line 3: decimal commas are not supported; use '.'");

  // OBJ: the BOM hid the first 'v' line, and its point was lost
  expect_points(read_cloud(file("bom.obj", "\xEF\xBB\xBFv 1 2 3\nv 4 5 6\n")), {V(1, 2, 3), V(4, 5, 6)});
  p = file("comma.obj", "v 1 2 3\nv 4,5 5,0 6,0\n");
  EXPECT_EQ(error_of(p), p + ": line 2: decimal commas are not supported; use '.'");

  // STL: an ASCII file with a BOM was taken for a binary one
  const std::vector<V> square = {V(0, 0, 0), V(1, 0, 0), V(1, 1, 0), V(0, 1, 0)};
  expect_points(read_cloud(file("bom.stl", std::string("\xEF\xBB\xBF") + kSquareAscii)), square);
  p = file("comma.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1,5 0 0\n");
  EXPECT_EQ(error_of(p), p + ": line 5: decimal commas are not supported; use '.'");
  // a binary STL with more bytes than its triangle count says: was read silently
  p = file("more.stl", square_binary("binary square") + std::string(50, '\0'));
  EXPECT_EQ(error_of(p), p + ": byte 184: 50 bytes after the last declared triangle (2 declared): the header's count "
                             "is smaller than the data");
}

// ---------------------------------------------------------------- dispatch

TEST_F(ReadCloud, ScaleAndExtensionCase) {
  PointCloud c;
  c.points = {V(1, -2, 0.5)};
  c.normals = {V(0, 0, 1)};
  write_ply(path("m.PLY"), c);
  PointCloud r = read_cloud(path("m.PLY"), 1000);
  expect_points(r, {V(1000, -2000, 500)});
  expect_normals(r, {V(0, 0, 1)});
}

TEST_F(ReadCloud, WholeFileErrors) {
  EXPECT_EQ(error_of(path("missing.ply")), path("missing.ply") + ": file does not exist");
  std::string p = file("empty.xyz", "");
  EXPECT_EQ(error_of(p), p + ": file is empty");
  fs::create_directories(path("d.ply"));
  EXPECT_EQ(error_of(path("d.ply")), path("d.ply") + ": is a directory, not a file");
  p = file("a.las", "x");
  EXPECT_EQ(error_of(p), p + ": unsupported extension '.las' (expected .ply .pcd .xyz .txt .csv .pts .off .obj .stl)");
  p = file("noext", "x");
  EXPECT_EQ(error_of(p), p + ": file name has no extension (expected .ply .pcd .xyz .txt .csv .pts .off .obj .stl)");
  p = file("a.xyz", "1 2 3\n");
  try {
    read_cloud(p, 0.0);
    ADD_FAILURE() << "no error";
  } catch (const CloudReadError& e) {
    EXPECT_EQ(std::string(e.what()), p + ": scale must be positive and finite, got 0");
  }
}

// Binary garbage under every extension: an error, never a crash.
TEST_F(ReadCloud, GarbageIsRejectedUnderEveryExtension) {
  std::string junk;
  std::uint32_t x = 12345;
  for (int i = 0; i < 3000; ++i) {
    x = x * 1664525u + 1013904223u;
    junk.push_back(static_cast<char>(x >> 24));
  }
  for (const char* ext : {".ply", ".pcd", ".xyz", ".csv", ".pts", ".off", ".stl"}) {
    const std::string p = file(std::string("junk") + ext, junk);
    EXPECT_NE(error_of(p), "<no error>") << ext;
  }
  // Every prefix of a valid binary PLY and PCD reads or fails cleanly.
  PointCloud c;
  c.points = kAwkward;
  c.normals = kNormals;
  write_ply(path("full.ply"), c);
  std::ifstream in(path("full.ply"), std::ios::binary);
  const std::string full((std::istreambuf_iterator<char>(in)), {});
  const std::string pcd = compressed_pcd(kAwkward, kNormals);
  // (A stride keeps the test fast; 3 and 5 are prime to the 8-byte values, so cuts land everywhere.)
  for (std::size_t n = 1; n < full.size(); n += 3) EXPECT_NE(error_of(file("cut.ply", full.substr(0, n))), "<no error>") << n;
  for (std::size_t n = 1; n < pcd.size(); n += 5) EXPECT_NE(error_of(file("cut.pcd", pcd.substr(0, n))), "<no error>") << n;
}

// ---------------------------------------------------------------- node

TEST_F(ReadCloud, NodeReadsAndScales) {
  const NodeDecl d = make_read_cloud_node();
  EXPECT_EQ(d.type, "io.read_cloud");
  ASSERT_NE(d.find_input("file"), nullptr);
  EXPECT_EQ(d.find_input("file")->type, "File");
  ASSERT_NE(d.find_output("cloud"), nullptr);
  EXPECT_EQ(d.find_output("cloud")->type, "Cloud");
  const ParamDecl* scale = d.find_param("scale");
  ASSERT_NE(scale, nullptr);
  EXPECT_EQ(scale->default_value, 1.0);
  EXPECT_EQ(*scale->min, 1e-9);
  EXPECT_EQ(*scale->max, 1e9);

  const std::string p = file("a.xyz", "1 2 3\n");
  auto run = [&](const std::string& path) {
    NodeContext ctx(d, "read", "part", {{"scale", 10.0}},
                    {{"file", std::make_shared<FileRef>(FileRef::open(path))}}, nullptr);
    d.run(ctx);
    return std::dynamic_pointer_cast<const PointCloud>(ctx.take_outputs().at("cloud"));
  };
  auto cloud = run(p);
  ASSERT_TRUE(cloud);
  expect_points(*cloud, {V(10, 20, 30)});

  const std::string bad = file("bad.xyz", "1 2 3\n1 2 x\n");
  try {
    run(bad);
    ADD_FAILURE() << "no error";
  } catch (const NodeError& e) {
    EXPECT_EQ(std::string(e.what()), bad + ": line 2: bad number 'x' in column 3");
  }
}

// Runs io.read_cloud on `path` with `scale`; returns the cloud and fills `warnings`.
std::shared_ptr<const PointCloud> run_read_node(const std::string& path, double scale,
                                                std::vector<std::string>& warnings) {
  const NodeDecl d = make_read_cloud_node();
  NodeContext ctx(d, "scan", "part", {{"scale", scale}}, {{"file", std::make_shared<FileRef>(FileRef::open(path))}},
                  nullptr, [&](const std::string& m) { warnings.push_back(m); });
  d.run(ctx);
  return std::dynamic_pointer_cast<const PointCloud>(ctx.take_outputs().at("cloud"));
}

// n x n grid of side `size` (mm), as XYZ text.
std::string grid_xyz(int n, double size) {
  std::string s;
  char buf[96];
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      std::snprintf(buf, sizeof buf, "%.17g %.17g %.17g\n", size * i / (n - 1), size * j / (n - 1), 0.01 * size * i / n);
      s += buf;
    }
  return s;
}

TEST_F(ReadCloud, NodeRefusesCoordinatesOutOfRangeAsBadInput) {
  // 1e300 overflowed the normals' sums: "coincident or collinear" was the message
  std::vector<std::string> warnings;
  const std::string p = file("far.xyz", "0 0 0\n1 0 0\n1e300 2 3\n");
  try {
    run_read_node(p, 1, warnings);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), p + ": point 2 at (1e+300, 2, 3): coordinates out of range (beyond 1e9 mm); the "
                                         "file is damaged or its scale is wrong");
  }
  // a scale can take a point there too
  try {
    run_read_node(file("big.xyz", "0 0 0\n2e6 0 0\n"), 1000, warnings);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path("big.xyz") + ": point 1 at (2e+09, 0, 0): coordinates out of range (beyond "
                                                       "1e9 mm); the file is damaged or its scale is wrong");
  }
  // and a malformed file is bad input too (scallop exits 2, not 1)
  EXPECT_THROW(run_read_node(file("bad.xyz", "1 2 3\n4 5 x\n"), 1, warnings), InputError);
}

TEST_F(ReadCloud, NodeWarnsWhenTheCloudDoesNotLookLikeMillimetres) {
  std::vector<std::string> warnings;
  // a 100 mm part written in metres: 0.1 across, points 0.00204 apart
  auto cloud = run_read_node(file("metres.xyz", grid_xyz(50, 0.1)), 1, warnings);
  EXPECT_EQ(cloud->size(), 2500u);
  EXPECT_EQ(warnings, std::vector<std::string>{"the cloud is 0.1 mm across with points 0.00204 mm apart: is it in "
                                               "metres? coordinates are read as mm; set scan.scale to 1000"});
  // 2 m across in metres, densely scanned in one corner: only the spacing gives it away
  warnings.clear();
  run_read_node(file("fine.xyz", grid_xyz(30, 0.01) + "2 0 0\n"), 1, warnings);
  EXPECT_EQ(warnings, std::vector<std::string>{"the cloud is 2 mm across with points 0.000345 mm apart: is it in "
                                               "metres? coordinates are read as mm; set scan.scale to 1000"});
  // micrometres: a 100 mm part with 50 x 50 points is 1e5 across, points 2040 apart
  warnings.clear();
  run_read_node(file("microns.xyz", grid_xyz(50, 1e5)), 1, warnings);
  EXPECT_EQ(warnings, std::vector<std::string>{"the cloud is 1e+05 mm across with points 2.04e+03 mm apart: is it in "
                                               "micrometres? coordinates are read as mm; set scan.scale to 0.001"});
  // the same part scaled right, and a part in mm: nothing to say
  warnings.clear();
  run_read_node(path("metres.xyz"), 1000, warnings);
  run_read_node(file("mm.xyz", grid_xyz(50, 100)), 1, warnings);
  EXPECT_EQ(warnings, std::vector<std::string>{});
}

// ---------------------------------------------------------------- real data

TEST(ReadCloudUnits, SpacingMatchesTheDensityAboveAndBelowTheSubsetSize) {
  // Uniform random points on a 100 x 100 mm square, density lambda per mm^2: the median distance
  // to the nearest other point is sqrt(ln 2 / (pi lambda)). Above 200 000 points the spacing comes
  // from a random 200 000 of them, scaled by sqrt(200 000 / n): the same figure.
  for (std::size_t n : {150000u, 600000u}) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0, 100);
    std::vector<Eigen::Vector3d> P(n);
    for (auto& p : P) p = Eigen::Vector3d(u(rng), u(rng), 5);
    const double lambda = static_cast<double>(n) / 1e4;
    const double expected = std::sqrt(std::log(2.0) / (std::numbers::pi * lambda));
    const CloudScale s = measure_scale(P);
    EXPECT_EQ(s.points, n);
    EXPECT_NEAR(s.extent, 100, 0.01);
    EXPECT_NEAR(s.spacing / expected, 1, 0.1) << n;  // a 1000-point sample's median: about 3 %
  }
}

TEST(ReadCloudRealData, SharedDataCountsAndBoxes) {
  const std::string root = std::string(SCALLOP_SOURCE_DIR) + "/../shared/data";
  if (!fs::exists(root)) GTEST_SKIP() << "../shared/data not found";
  struct Case {
    const char* file;
    std::size_t count;
    V lo, hi;  // bounding box of the finite points, from PROVENANCE.md (6 significant digits)
  };
  const Case cases[] = {
      {"cturtle/cturtle.pcd", 167198, V(-1.41972, -1.04969, 1.3961), V(1.41972, 1.06472, 2)},
      {"bunny_scan/bun000.ply", 40256, V(-0.09475, 0.0357363, -0.0586982), V(0.061, 0.18794, 0.0587228)},
      {"milk_kinect/milk.pcd", 13704, V(-0.140083, -0.26378, 0.714), V(0.0138067, -0.0117286, 0.891)},
      {"camelhead/camelhead.off", 11381, V(-0.261816, -0.329475, -0.532113), V(0.26182, 0.202191, 0.467887)},
      {"hemisphere/hemisphere.off", 1861, V(-0.995185, -0.995185, 0.0980171), V(0.995185, 0.995185, 1)},
      {"fandisk/fandisk.off", 6475, V(-0.920571, -1, -0.511065), V(0.920571, 1, 0.511065)},
      {"fandisk/fandisk_quads.off", 766, V(-2.39948e-11, 12.6055, -2.68026), V(4.8279, 17.85, 7.15269e-11)},
      {"face_bust/face.obj", 25905, V(-12.1265, 147.778, -15.0857), V(12.1265, 181.968, 11.2667)},
      {"block/block.off", 2132, V(-8.2, -9.99999, -19.0001), V(11.7999, 9.99992, 19.0001)},
      {"abc_00000050/00000050_80d90bfdd2e74e709956122a_trimesh_000.stl", 3795,
       V(-0.0323494, -0.0049403, -0.0323595), V(0.0323595, 0.0015875, 0.0858575)},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.file);
    const std::string p = root + "/" + c.file;
    if (!fs::exists(p)) {
      ADD_FAILURE() << p << " is missing";
      continue;
    }
    const PointCloud r = read_cloud(p);
    EXPECT_EQ(r.size(), c.count);
    EXPECT_FALSE(r.has_normals());
    V lo = V::Constant(INFINITY), hi = V::Constant(-INFINITY);
    for (const V& q : r.points)
      if (q.allFinite()) lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(lo[k], c.lo[k], 5e-6 * std::max(1.0, std::abs(c.lo[k])));
      EXPECT_NEAR(hi[k], c.hi[k], 5e-6 * std::max(1.0, std::abs(c.hi[k])));
    }
  }
}

}  // namespace
}  // namespace scallop
