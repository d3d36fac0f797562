/* SPDX-License-Identifier: BSD-3-Clause */
/* Loading and saving pcl::PCLPointCloud2 for the pcl_dacpo_* tools
 * (dacpo_tool_io.h): the file checked before PCL reads it, outputs written
 * through a checked, synced temporary file. */
#include "dacpo_tool_io.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fcntl.h>
#include <sstream>
#include <string>
#include <unistd.h>
#include <utility>
#include <vector>

namespace dacpo_tool {

bool
loadCloud2(const std::string& path, pcl::PCLPointCloud2& cloud, std::string& error)
{
  struct stat st;
  if (stat(path.c_str(), &st) != 0) {
    error = "cannot open '" + path + "': " + std::strerror(errno);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    error = "'" + path + "' is not a regular file";
    return false;
  }
  if (st.st_size == 0) {
    error = "'" + path + "' is empty (0 bytes)";
    return false;
  }
  const std::string ext = extension(path);
  if ((ext == ".pcd" || ext == ".ply") &&
      !checkCloudFile(path, static_cast<long long>(st.st_size), error))
    return false;
  if (ext != ".pcd" && ext != ".ply") {
    error = "'" + path + "': unknown extension (use .pcd or .ply)";
    return false;
  }
  int rc = -1;
  /* PCL's readers throw on some headers the checks above let through (a
   * field name with bytes that split it in two: std::out_of_range). */
  try {
    if (ext == ".pcd") {
      pcl::PCDReader reader;
      rc = reader.read(path, cloud);
    }
    else {
      pcl::PLYReader reader;
      rc = reader.read(path, cloud);
    }
  } catch (const std::exception& e) {
    error = "cannot read '" + path + "': " + e.what();
    return false;
  }
  if (rc < 0) {
    error = "cannot read '" + path + "' (not a valid " + ext.substr(1) +
            " file, or truncated)";
    return false;
  }
  const std::size_t points = static_cast<std::size_t>(cloud.width) * cloud.height;
  if (cloud.data.size() != points * cloud.point_step) {
    error = "'" + path + "' is truncated or inconsistent: header says " +
            std::to_string(points) + " points, data holds " +
            std::to_string(cloud.point_step ? cloud.data.size() / cloud.point_step : 0);
    return false;
  }
  if (pcl::getFieldIndex(cloud, "x") < 0 || pcl::getFieldIndex(cloud, "y") < 0 ||
      pcl::getFieldIndex(cloud, "z") < 0) {
    error = "'" + path + "' has no x, y, z fields";
    return false;
  }
  return true;
}

std::string
ioError(const std::string& what, const std::string& path)
{
  return what + " '" + path + "': " + std::strerror(errno);
}

bool
writeAllChecked(const std::string& path,
                const std::string& bytes,
                std::string& error,
                const std::string& shown)
{
  const std::string& name = shown.empty() ? path : shown;
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    error = ioError("cannot create", name);
    return false;
  }
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t w = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (w < 0 && errno == EINTR)
      continue;
    if (w <= 0) {
      error = ioError("cannot write", name);
      ::close(fd);
      return false;
    }
    done += static_cast<std::size_t>(w);
  }
  if (::fsync(fd) != 0) {
    error = ioError("cannot sync", name);
    ::close(fd);
    return false;
  }
  if (::close(fd) != 0) {
    error = ioError("cannot close", name);
    return false;
  }
  return true;
}

bool
syncFile(const std::string& path, std::string& error)
{
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) {
    error = ioError("cannot reopen", path);
    return false;
  }
  const bool ok = ::fsync(fd) == 0;
  if (!ok)
    error = ioError("cannot sync", path);
  ::close(fd);
  return ok;
}

namespace {

/* PCL's binary PLY writer formats the body value by value through a stream
 * (about 0.4 s for 500K points of 8 fields); for the clouds whose bytes it
 * writes as they are stored, one copy per field does the same. It writes
 * otherwise: organized clouds (a range grid), colour fields (rgb, rgba: split
 * into uchar properties), fields of several values (lists), normals that are
 * not float (the header says float), and byte orders other than the host's. */
bool
storedAsPly(const pcl::PCLPointCloud2& cloud)
{
  const std::uint16_t probe = 1;
  unsigned char first;
  std::memcpy(&first, &probe, 1);
  if (cloud.height != 1 || cloud.width == 0 || cloud.is_bigendian != (first == 0) ||
      cloud.data.size() != static_cast<std::size_t>(cloud.width) * cloud.point_step)
    return false;
  for (const auto& f : cloud.fields) {
    const std::size_t size = pcl::getFieldSize(f.datatype);
    if (f.count != 1 || size == 0 || f.offset + size > cloud.point_step ||
        f.name.find("rgb") != std::string::npos)
      return false;
    if (f.name.rfind("normal_", 0) == 0 && f.datatype != pcl::PCLPointField::FLOAT32)
      return false;
  }
  return true;
}

/* The header PCL writes (no camera element), then each point's fields in
 * order. */
std::string
plyBytes(const pcl::PCLPointCloud2& cloud)
{
  pcl::PLYWriter writer;
  std::string bytes = writer.generateHeaderBinary(cloud,
                                                  Eigen::Vector4f::Zero(),
                                                  Eigen::Quaternionf::Identity(),
                                                  static_cast<int>(cloud.width),
                                                  false);
  std::vector<std::pair<std::size_t, std::size_t>> spans; /* offset, size */
  std::size_t row = 0;
  for (const auto& f : cloud.fields) {
    spans.emplace_back(f.offset, pcl::getFieldSize(f.datatype));
    row += spans.back().second;
  }
  const std::size_t head = bytes.size();
  bytes.resize(head + row * cloud.width);
  char* out = &bytes[head];
  const std::uint8_t* in = cloud.data.data();
  for (std::size_t i = 0; i < cloud.width; ++i, in += cloud.point_step)
    for (const auto& span : spans) {
      std::memcpy(out, in + span.first, span.second);
      out += span.second;
    }
  return bytes;
}

} // namespace

bool
saveCloud2(const std::string& path,
           const pcl::PCLPointCloud2& cloud,
           std::string& error)
{
  const std::string ext = extension(path);
  if (ext != ".pcd" && ext != ".ply") {
    error = "'" + path + "': unknown extension (use .pcd or .ply)";
    return false;
  }
  return writeAtomically(
      path,
      [&](const std::string& tmp, std::string& err) {
        if (ext == ".pcd") {
          std::ostringstream os;
          pcl::PCDWriter writer;
          if (writer.writeBinaryCompressed(os, cloud) < 0 || !os) {
            err = "cannot encode '" + path + "' as PCD";
            return false;
          }
          return writeAllChecked(tmp, os.str(), err, path);
        }
        if (storedAsPly(cloud))
          return writeAllChecked(tmp, plyBytes(cloud), err, path);
        pcl::PLYWriter writer;
        const int rc = writer.writeBinary(
            tmp, cloud, Eigen::Vector4f::Zero(), Eigen::Quaternionf::Identity(), false);
        struct stat st;
        const long long want = expectedBinaryPlySize(tmp);
        if (rc < 0 || ::stat(tmp.c_str(), &st) != 0 || want == 0 ||
            st.st_size != want) {
          err =
              "cannot write '" + path + "' (short write: disk full or no permission?)";
          return false;
        }
        return true;
      },
      error);
}

} // namespace dacpo_tool
