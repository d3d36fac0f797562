/* SPDX-License-Identifier: BSD-3-Clause */
/* Shared by the pcl_dacpo_* tools: load and save pcl::PCLPointCloud2 by
 * extension with clear errors (the file checked first), every output written
 * through a temporary file, checked, synced and renamed. Includes the other
 * tool headers: options (dacpo_tool_options.h), file checks
 * (dacpo_tool_file_checks.h) and fields (dacpo_tool_fields.h). Header-only,
 * tools only (not installed). */
#pragma once

#include "dacpo_tool_fields.h"
#include "dacpo_tool_file_checks.h"
#include "dacpo_tool_options.h"

#include "dacpo_cleanup.h"
#include "dacpo_paths.h"
#include <pcl/common/io.h>
#include <pcl/console/print.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/PCLPointCloud2.h>
#include <pcl/point_types.h>

#include <sys/stat.h>

#include <algorithm>
#include <exception>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <limits>
#include <sstream>
#include <string>
#include <unistd.h>
#include <vector>

namespace dacpo_tool {

/** Loads a .pcd or .ply into \a cloud and checks it is complete and has x, y, z.
 *  On failure returns false with a message in \a error. */
inline bool
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
  }
  catch (const std::exception& e) {
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

/* ---- safe output -------------------------------------------------------
 * A tool never leaves a half-written file, nor destroys the one it replaces
 * (`pcl_dacpo_orient scan.ply scan.ply` on a full disk): every output goes to a
 * temporary file in the target's folder, is checked, synced to disk and only
 * then renamed over the target. PCL's writers do not report write errors (and
 * its PCD writer maps the file, which dies with SIGBUS on a full disk), so PCD
 * data is produced in memory and written here with every call checked, and
 * PLY files written by PCL are read back and their size checked. */

/** errno as text, with the path. */
inline std::string
ioError(const std::string& what, const std::string& path)
{
  return what + " '" + path + "': " + std::strerror(errno);
}

/** Writes \a bytes to \a path (created or truncated), checking every write,
 *  fsync and close; messages name \a shown (the file the user asked for). */
inline bool
writeAllChecked(const std::string& path,
                const std::string& bytes,
                std::string& error,
                const std::string& shown = std::string())
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

/** fsync of a file written by someone else (PCL). */
inline bool
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

/** Produces \a path through a temporary file beside it: \a produce writes the
 *  temporary file (given its name), then it is synced and renamed over \a path.
 *  On any failure the temporary file is removed and \a path is untouched. */
template <typename Produce>
bool
writeAtomically(const std::string& path, Produce produce, std::string& error)
{
  char name[4352];
  if (dacpo_temp_sibling(path.c_str(), "tmp", static_cast<long>(::getpid()), name,
                         sizeof(name)) != 0) {
    error = "'" + path + "': name too long for a temporary file beside it";
    return false;
  }
  const std::string tmp = name;
  /* a SIGINT or SIGTERM while it is written removes it (dacpo_cleanup.h) */
  const int slot = dacpo_cleanup_add(tmp.c_str());
  const bool ok = produce(tmp, error) && syncFile(tmp, error);
  if (ok && std::rename(tmp.c_str(), path.c_str()) == 0) {
    dacpo_cleanup_drop(slot);
    return true;
  }
  if (ok)
    error = ioError("cannot replace", path);
  std::remove(tmp.c_str());
  dacpo_cleanup_drop(slot);
  return false;
}

/** Writes binary-compressed PCD or binary PLY by extension, safely (above). */
inline bool
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
