// SPDX-License-Identifier: BSD-3-Clause
// Tests of the PLY and PCD header parsers of wrappers/support as the tools'
// file checks use them (dacpo_ply_read_header, dacpo_ply_binary_size,
// dacpo_pcd_read_header): what a header declares, where the data starts, and
// the message and line of a bad header.
#include <gtest/gtest.h>

#include <cstdio>
#include <memory>
#include <string>
#include <unistd.h>

extern "C" {
#include "dacpo_pcd.h"
}

namespace {

std::string
TempPath(const std::string& name)
{
  return testing::TempDir() + "dacpo_headers_" + std::to_string(getpid()) + "_" + name;
}

void
WriteFile(const std::string& path, const std::string& bytes)
{
  FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  std::fwrite(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
}

// Parses the PLY header of bytes; the status, the info and the message.
int
PlyHeader(const std::string& bytes,
          dacpo_ply_header_info* info,
          std::string* msg,
          long* at)
{
  const std::string path = TempPath("h.ply");
  WriteFile(path, bytes);
  FILE* f = std::fopen(path.c_str(), "rb");
  char err[512] = "";
  const int rc = dacpo_ply_read_header(f, path.c_str(), info, err, sizeof(err));
  *at = std::ftell(f);
  std::fclose(f);
  std::remove(path.c_str());
  *msg = err;
  return rc;
}

int
PcdHeader(const std::string& bytes, dacpo_pcd_header* h, std::string* msg, long* at)
{
  const std::string path = TempPath("h.pcd");
  WriteFile(path, bytes);
  FILE* f = std::fopen(path.c_str(), "rb");
  char err[512] = "";
  const int rc = dacpo_pcd_read_header(f, path.c_str(), h, err, sizeof(err));
  *at = std::ftell(f);
  std::fclose(f);
  std::remove(path.c_str());
  *msg = err;
  return rc;
}

// A string of a literal with NUL bytes in it.
template <std::size_t N>
std::string
Bytes(const char (&text)[N])
{
  return std::string(text, N - 1);
}

const std::string kPly =
    "ply\nformat binary_little_endian 1.0\ncomment a\n"
    "element vertex 2\nproperty float x\nproperty double y\n"
    "element range_grid 2\nproperty list uchar int vertex_indices\n"
    "end_header\n";

} // namespace

TEST(DacpoPointHeaders, PlyHeaderDeclaresElementsAndWhereTheDataStarts)
{
  auto info = std::make_unique<dacpo_ply_header_info>();
  std::string msg;
  long at = 0;
  ASSERT_EQ(PlyHeader(kPly + std::string(40, '\0'), info.get(), &msg, &at),
            DACPO_PLY_OK)
      << msg;
  EXPECT_EQ(info->format, DACPO_PLY_BINARY_LE);
  ASSERT_EQ(info->nelements, 2);
  EXPECT_STREQ(info->elements[0].name, "vertex");
  EXPECT_EQ(info->elements[0].count, 2u);
  ASSERT_EQ(info->elements[0].nprops, 2);
  EXPECT_EQ(info->elements[0].props[1].bytes, 8);
  EXPECT_EQ(info->elements[0].props[1].count_bytes, 0);
  EXPECT_EQ(info->elements[1].props[0].bytes, 4);
  EXPECT_EQ(info->elements[1].props[0].count_bytes, 1);
  EXPECT_EQ(info->data_offset, kPly.size());
  EXPECT_EQ(at, static_cast<long>(kPly.size()));
  EXPECT_EQ(info->lines, 9);
}

TEST(DacpoPointHeaders, PlyBinarySizeWalksListRows)
{
  // vertex rows: 2 x 12 bytes; range_grid rows: a list of 1 int, then of 0
  const std::string data = std::string(24, '\0') + std::string("\x01", 1) +
                           std::string(4, '\0') + std::string(1, '\0');
  const std::string path = TempPath("size.ply");
  WriteFile(path, kPly + data);
  unsigned long long bytes = 0;
  char err[512] = "";
  EXPECT_EQ(dacpo_ply_binary_size(path.c_str(), &bytes, err, sizeof(err)), DACPO_PLY_OK)
      << err;
  EXPECT_EQ(bytes, kPly.size() + data.size());
  // a list row that runs past the end of the file, and ASCII, cannot be told
  WriteFile(path, kPly + std::string(24, '\0') + std::string("\x01", 1));
  EXPECT_NE(dacpo_ply_binary_size(path.c_str(), &bytes, err, sizeof(err)),
            DACPO_PLY_OK);
  EXPECT_EQ(bytes, 0u);
  WriteFile(path, "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n");
  EXPECT_NE(dacpo_ply_binary_size(path.c_str(), &bytes, err, sizeof(err)),
            DACPO_PLY_OK);
  std::remove(path.c_str());
}

TEST(DacpoPointHeaders, PlyHeaderErrorsNameTheLine)
{
  auto info = std::make_unique<dacpo_ply_header_info>();
  std::string msg;
  long at = 0;
  struct Case {
    std::string text;
    const char* says;
  } cases[] = {
      {"PLY\n", "line 1: the file does not start with 'ply'"},
      {"ply\nformat ascii 1.0\nelement vertex x\nend_header\n",
       "line 3: bad count 'x' for element 'vertex'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n",
       "line 4: unknown property type"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int "
       "i\nend_header\n",
       "line 4: bad list property types"},
      {"ply\nformat ascii 1.0\nbogus\nend_header\n", "line 3: unknown keyword 'bogus'"},
      {Bytes("ply\nformat ascii 1.0\ncomment a\0b\nend_header\n"),
       "line 3: binary bytes in the header"},
      {"ply\nelement vertex 0\nend_header\n", "line 3: no format line"},
      {"ply\nformat ascii 1.0\nelement vertex 0\n",
       "line 3: the header ends before 'end_header'"},
  };
  for (const Case& k : cases) {
    EXPECT_EQ(PlyHeader(k.text, info.get(), &msg, &at), DACPO_PLY_ERR_FORMAT) << k.says;
    EXPECT_NE(msg.find("is not a valid PLY file: " + std::string(k.says)),
              std::string::npos)
        << "expected '" << k.says << "', got " << msg;
  }
  // blanks around keywords, a long comment and a last line without its
  // newline are accepted
  const std::string ok = " ply \nformat ascii 1.0\n  comment x\ncomment " +
                         std::string(5000, 'a') + "\nelement vertex 0\nend_header";
  EXPECT_EQ(PlyHeader(ok, info.get(), &msg, &at), DACPO_PLY_OK) << msg;
  EXPECT_EQ(info->format, DACPO_PLY_ASCII);
  EXPECT_EQ(info->lines, 6);
}

TEST(DacpoPointHeaders, PcdHeaderDeclaresFieldsAndErrorsNameTheLine)
{
  dacpo_pcd_header h;
  std::string msg;
  long at = 0;
  const std::string head = "\n  # .PCD v0.7\nVERSION 0.7\nFIELDS x y rgb\nSIZE 4 8 4\n"
                           "TYPE F F U\nCOUNT 1 1 2\nWIDTH 2\nPOINTS 2\nDATA binary\n";
  ASSERT_EQ(PcdHeader(head + "rest", &h, &msg, &at), DACPO_PLY_OK) << msg;
  EXPECT_EQ(h.nf, 3);
  EXPECT_EQ(h.f[1].offset, 4u);
  EXPECT_EQ(h.f[2].count, 2u);
  EXPECT_EQ(h.record, 20u);
  EXPECT_TRUE(h.have_width && h.have_points && !h.have_height);
  EXPECT_STREQ(h.data, "binary");
  EXPECT_EQ(h.lines, 10);
  EXPECT_EQ(at, static_cast<long>(head.size()));

  struct Case {
    std::string text;
    const char* says;
  } cases[] = {
      {"ply\nformat ascii 1.0\n", "line 1: unexpected 'ply' (not a PCD file?)"},
      {Bytes("# x\nVERSION\0 0.7\n"), "line 2: binary bytes in the header"},
      {"FIELDS x\nSIZE 3\n", "line 2: bad SIZE '3'"},
      {"SIZE 4\n", "line 1: unexpected 'SIZE 4' (not a PCD file?)"},
      {"FIELDS x\nTYPE F\nSIZE 4 4\n", "line 3: SIZE has 2 values for 1 fields"},
      {"FIELDS x\nSIZE 4\nTYPE F\nDATA gzip\n", "line 4: unknown DATA 'gzip'"},
      {"FIELDS x\nSIZE 4\nDATA ascii\n", "line 3: FIELDS, SIZE and TYPE are required"},
      {"# x\nFIELDS x\n", "line 2: no DATA line"},
  };
  for (const Case& k : cases) {
    EXPECT_EQ(PcdHeader(k.text, &h, &msg, &at), DACPO_PLY_ERR_FORMAT) << k.says;
    EXPECT_NE(msg.find("is not a valid PCD file: " + std::string(k.says)),
              std::string::npos)
        << "expected '" << k.says << "', got " << msg;
  }
}
