// SPDX-License-Identifier: BSD-3-Clause
// Tests of the plain-C PCD reader/writer in wrappers/support (dacpo_pcd.c):
// hand-written files with known values in every DATA kind, field types and
// layouts, and the errors of bad files. PCL's own writer and reader are checked
// against it in tests/pcl_dacpo/test_pcd_interop.cpp.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <string>
#include <unistd.h>
#include <vector>

extern "C" {
#include "dacpo_pcd.h"
}

namespace {

std::string
TempPath(const std::string& name)
{
  return testing::TempDir() + "dacpo_pcd_" + std::to_string(getpid()) + "_" + name;
}

void
WriteFile(const std::string& path,
          const std::string& header,
          const std::vector<uint8_t>& data)
{
  FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(header.data(), 1, header.size(), f);
  if (!data.empty())
    std::fwrite(data.data(), 1, data.size(), f);
  std::fclose(f);
}

// Little-endian bytes of a value.
template <typename T>
void
Put(std::vector<uint8_t>& out, T v)
{
  uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.insert(out.end(), b, b + sizeof(T)); // the test machines are little-endian
}

// Reads path; returns the status and the error text.
int
Read(const std::string& path, dacpo_ply_cloud* c, std::string* msg = nullptr)
{
  char err[512] = "";
  const int rc = dacpo_points_read(path.c_str(), c, err, sizeof(err));
  if (msg)
    *msg = err;
  return rc;
}

const char* kHead3 = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";

} // namespace

TEST(DacpoPcd, WriteReadRoundTripIsBitExact)
{
  const std::string path = TempPath("roundtrip.pcd");
  std::vector<float> xyz, nrm;
  for (int i = 0; i < 1000; ++i) {
    xyz.insert(xyz.end(), {0.001f * i, -1.0f / (i + 1), 3.0e5f + i});
    nrm.insert(nrm.end(), {0.0f, (i % 2) ? 1.0f : -1.0f, 0.0f});
  }
  char err[256];
  ASSERT_EQ(
      dacpo_points_write(
          path.c_str(), xyz.data(), nrm.data(), 1000, "one\ntwo", err, sizeof(err)),
      DACPO_PLY_OK)
      << err;
  dacpo_ply_cloud c;
  ASSERT_EQ(Read(path, &c), DACPO_PLY_OK);
  ASSERT_EQ(c.n, 1000u);
  ASSERT_NE(c.normals, nullptr);
  EXPECT_EQ(std::memcmp(c.xyz, xyz.data(), xyz.size() * sizeof(float)), 0);
  EXPECT_EQ(std::memcmp(c.normals, nrm.data(), nrm.size() * sizeof(float)), 0);
  dacpo_ply_cloud_free(&c);

  // positions only, then an empty cloud
  ASSERT_EQ(
      dacpo_pcd_write(path.c_str(), xyz.data(), nullptr, 10, nullptr, err, sizeof(err)),
      DACPO_PLY_OK);
  ASSERT_EQ(Read(path, &c), DACPO_PLY_OK);
  EXPECT_EQ(c.n, 10u);
  EXPECT_EQ(c.normals, nullptr);
  EXPECT_EQ(std::memcmp(c.xyz, xyz.data(), 30 * sizeof(float)), 0);
  dacpo_ply_cloud_free(&c);
  ASSERT_EQ(
      dacpo_pcd_write(path.c_str(), nullptr, nullptr, 0, nullptr, err, sizeof(err)),
      DACPO_PLY_OK);
  ASSERT_EQ(Read(path, &c), DACPO_PLY_OK);
  EXPECT_EQ(c.n, 0u);
  dacpo_ply_cloud_free(&c);
  std::remove(path.c_str());
}

TEST(DacpoPcd, AsciiWithExtraFieldsCountsAndTypes)
{
  const std::string path = TempPath("ascii.pcd");
  WriteFile(path,
            std::string(kHead3) +
                "FIELDS rgb x _ y z normal_x normal_y normal_z\n"
                "SIZE 4 4 1 4 4 4 4 4\nTYPE U F I F F F F F\nCOUNT 1 1 3 1 1 1 1 1\n"
                "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
                "7 1.5 0 0 0 2.5 3.5 0 0 1\n8 -1 9 9 9 -2 -3 1 0 0\n",
            {});
  dacpo_ply_cloud c;
  std::string msg;
  ASSERT_EQ(Read(path, &c, &msg), DACPO_PLY_OK) << msg;
  ASSERT_EQ(c.n, 2u);
  ASSERT_NE(c.normals, nullptr);
  const float want_xyz[6] = {1.5f, 2.5f, 3.5f, -1.0f, -2.0f, -3.0f};
  const float want_nrm[6] = {0, 0, 1, 1, 0, 0};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(c.xyz[i], want_xyz[i]) << i;
    EXPECT_EQ(c.normals[i], want_nrm[i]) << i;
  }
  dacpo_ply_cloud_free(&c);

  // normal_x alone: positions only; nan points are passed on
  WriteFile(path,
            std::string(kHead3) +
                "FIELDS x y z normal_x\nSIZE 4 4 4 4\nTYPE F F F F\nWIDTH 2\nHEIGHT 1\n"
                "POINTS 2\nDATA ascii\nnan nan nan 0\n1 2 3 0\n",
            {});
  ASSERT_EQ(Read(path, &c, &msg), DACPO_PLY_OK) << msg;
  ASSERT_EQ(c.n, 2u);
  EXPECT_EQ(c.normals, nullptr);
  EXPECT_TRUE(c.xyz[0] != c.xyz[0]);
  EXPECT_EQ(c.xyz[5], 3.0f);
  dacpo_ply_cloud_free(&c);
  std::remove(path.c_str());
}

TEST(DacpoPcd, BinaryIntegerAndDoubleFields)
{
  const std::string path = TempPath("binary.pcd");
  // x int16, y int8, z uint32, a skipped uint16 pair, then double normals;
  // WIDTH x HEIGHT gives the count (no POINTS line, as in version 0.6)
  std::vector<uint8_t> d;
  const int16_t xs[2] = {-5, 300};
  const int8_t ys[2] = {-1, 7};
  const uint32_t zs[2] = {70000u, 0u};
  for (int i = 0; i < 2; ++i) {
    Put(d, xs[i]);
    Put(d, ys[i]);
    Put(d, zs[i]);
    Put(d, uint16_t(0xBEEF));
    Put(d, uint16_t(0xCAFE));
    Put(d, 0.25 * (i + 1));
    Put(d, -0.5);
    Put(d, 1.0);
  }
  WriteFile(path,
            "FIELDS x y z pad normal_x normal_y normal_z\nSIZE 2 1 4 2 8 8 8\n"
            "TYPE I I U U F F F\nCOUNT 1 1 1 2 1 1 1\nWIDTH 1\nHEIGHT 2\nDATA binary\n",
            d);
  dacpo_ply_cloud c;
  std::string msg;
  ASSERT_EQ(Read(path, &c, &msg), DACPO_PLY_OK) << msg;
  ASSERT_EQ(c.n, 2u);
  const float want_xyz[6] = {-5, -1, 70000, 300, 7, 0};
  const float want_nrm[6] = {0.25f, -0.5f, 1, 0.5f, -0.5f, 1};
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(c.xyz[i], want_xyz[i]) << i;
    EXPECT_EQ(c.normals[i], want_nrm[i]) << i;
  }
  dacpo_ply_cloud_free(&c);
  std::remove(path.c_str());
}

TEST(DacpoPcd, BinaryCompressedLiteralRunAndBackReference)
{
  const std::string path = TempPath("lzf.pcd");
  // Two points; the fields one after another: x0 x1 y0 y1 z0 z1 = 1 2 3 4 5 1.
  // LZF: a literal run of the first 20 bytes (control 19), then z1 as a
  // reference of 4 bytes to distance 20 (control 0x40, then 19).
  std::vector<uint8_t> raw;
  for (float v : {1.0f, 2.0f, 3.0f, 4.0f, 5.0f})
    Put(raw, v);
  std::vector<uint8_t> lzf;
  lzf.push_back(19);
  lzf.insert(lzf.end(), raw.begin(), raw.end());
  lzf.push_back(0x40);
  lzf.push_back(19);
  std::vector<uint8_t> d;
  Put(d, uint32_t(lzf.size()));
  Put(d, uint32_t(24));
  d.insert(d.end(), lzf.begin(), lzf.end());
  const std::string head =
      std::string(kHead3) +
      "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n"
      "HEIGHT 1\nPOINTS 2\nDATA binary_compressed\n";
  WriteFile(path, head, d);
  dacpo_ply_cloud c;
  std::string msg;
  ASSERT_EQ(Read(path, &c, &msg), DACPO_PLY_OK) << msg;
  ASSERT_EQ(c.n, 2u);
  const float want[6] = {1, 3, 5, 2, 4, 1};
  for (int i = 0; i < 6; ++i)
    EXPECT_EQ(c.xyz[i], want[i]) << i;
  dacpo_ply_cloud_free(&c);

  // a reference before the start of the output: corrupt, not a crash
  std::vector<uint8_t> bad = d;
  bad[bad.size() - 1] = 200;
  WriteFile(path, head, bad);
  EXPECT_EQ(Read(path, &c, &msg), DACPO_PLY_ERR_FORMAT);
  EXPECT_NE(msg.find("corrupt"), std::string::npos) << msg;
  EXPECT_EQ(c.xyz, nullptr);
  // an expanded size that does not match the header
  bad = d;
  bad[4] = 20;
  WriteFile(path, head, bad);
  EXPECT_EQ(Read(path, &c, &msg), DACPO_PLY_ERR_FORMAT);
  EXPECT_NE(msg.find("expands to 20 bytes"), std::string::npos) << msg;
  // cut short
  bad.assign(d.begin(), d.end() - 5);
  WriteFile(path, head, bad);
  EXPECT_EQ(Read(path, &c, &msg), DACPO_PLY_ERR_FORMAT);
  EXPECT_NE(msg.find("truncated"), std::string::npos) << msg;
  std::remove(path.c_str());
}

TEST(DacpoPcd, BadFilesGiveErrorsNotCrashes)
{
  const std::string path = TempPath("bad.pcd");
  dacpo_ply_cloud c;
  std::string msg;
  EXPECT_EQ(Read(TempPath("missing.pcd"), &c, &msg), DACPO_PLY_ERR_IO);
  EXPECT_NE(msg.find("cannot open"), std::string::npos) << msg;

  const std::string fields = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  const std::string good =
      std::string(kHead3) + fields + "WIDTH 2\nHEIGHT 1\nPOINTS 2\n";
  struct Case {
    std::string text;
    const char* says;
  } cases[] = {
      {"ply\nformat binary_little_endian 1.0\n", "not a PCD file"},
      {good, "no DATA line"},
      {good + "DATA binary\n" + std::string(13, '\0'),
       "truncated: 2 points need more than the 13 bytes left"},
      {good + "DATA ascii\n1 2 3\n4 5\n", "truncated: 2 points need more than the 10"},
      {good + "DATA ascii\n1 2 3\n4 5      \n", "truncated: 1 of 2 points"},
      {std::string(kHead3) + fields + "POINTS 4000000000\nDATA binary_compressed\n" +
           std::string(64, 'x'),
       "truncated: 4000000000 points"},
      {good + "DATA ascii\n1 2 3\n4 five 6\n", "'five' is not a number"},
      {good + "DATA ascii\n1 2 3\n4 5 6 7\n", "values after the last of 2 points"},
      {good + "DATA ascii\n1 2 3\n4 5 " + std::string(200, '6') + "\n",
       "is not a number"},
      {good + "DATA gzip\n", "unknown DATA 'gzip'"},
      {std::string(kHead3) +
           "FIELDS x y\nSIZE 4 4\nTYPE F F\nPOINTS 1\nDATA ascii\n1 2\n",
       "x, y and z are required"},
      {std::string(kHead3) +
           "FIELDS x y z\nSIZE 4 3 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n",
       "bad SIZE '3'"},
      {std::string(kHead3) +
           "FIELDS x y z\nSIZE 4 2 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n",
       "float of 2 bytes"},
      {std::string(kHead3) +
           "FIELDS x y z\nSIZE 4 4 4\nTYPE F D F\nPOINTS 1\nDATA ascii\n",
       "TYPE 'D'"},
      {std::string(kHead3) +
           "FIELDS x y z\nSIZE 4 4\nTYPE F F F\nPOINTS 1\nDATA ascii\n",
       "SIZE has 2 values for 3 fields"},
      {std::string(kHead3) + fields + "HEIGHT 1\nDATA ascii\n",
       "neither POINTS nor WIDTH"},
      {std::string(kHead3) + fields + "POINTS -3\nDATA ascii\n", "bad POINTS"},
      {std::string(kHead3) + fields + "COLOUR 1\nDATA ascii\n",
       "unknown keyword 'COLOUR'"},
      {std::string(kHead3) + "DATA ascii\n", "FIELDS, SIZE and TYPE are required"},
      {std::string(kHead3) + fields + "POINTS 99999999999999999999\nDATA ascii\n",
       "bad POINTS"},
  };
  for (const Case& k : cases) {
    WriteFile(path, k.text, {});
    EXPECT_EQ(Read(path, &c, &msg), DACPO_PLY_ERR_FORMAT) << k.says;
    EXPECT_NE(msg.find(k.says), std::string::npos)
        << "expected '" << k.says << "', got " << msg;
    EXPECT_EQ(c.n, 0u);
    EXPECT_EQ(c.xyz, nullptr);
  }
  // an unwritable output
  char err[256] = "";
  const float p[3] = {0, 0, 0};
  EXPECT_EQ(
      dacpo_points_write(
          (TempPath("no_dir") + "/x.pcd").c_str(), p, nullptr, 1, nullptr, err, 256),
      DACPO_PLY_ERR_IO);
  EXPECT_NE(std::string(err).find("cannot open"), std::string::npos) << err;
  std::remove(path.c_str());
}

TEST(DacpoPcd, ExtensionChoosesTheFormat)
{
  EXPECT_EQ(dacpo_is_pcd_path("a/b.pcd"), 1);
  EXPECT_EQ(dacpo_is_pcd_path("B.PCD"), 1);
  EXPECT_EQ(dacpo_is_pcd_path("b.ply"), 0);
  EXPECT_EQ(dacpo_is_pcd_path("pcd"), 0);
  EXPECT_EQ(dacpo_is_pcd_path(nullptr), 0);
  const float p[3] = {1, 2, 3};
  char err[256];
  const std::string ply = TempPath("x.ply");
  ASSERT_EQ(dacpo_points_write(ply.c_str(), p, nullptr, 1, nullptr, err, 256),
            DACPO_PLY_OK);
  FILE* f = std::fopen(ply.c_str(), "rb");
  ASSERT_NE(f, nullptr);
  char magic[4] = {0};
  EXPECT_EQ(std::fread(magic, 1, 3, f), 3u);
  std::fclose(f);
  EXPECT_STREQ(magic, "ply");
  std::remove(ply.c_str());
}
