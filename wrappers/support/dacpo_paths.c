/* SPDX-License-Identifier: BSD-3-Clause */
#include "dacpo_paths.h"

#include "dacpo_support_err.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef NAME_MAX
#define NAME_MAX 255
#endif
#ifndef PATH_MAX
#define PATH_MAX 4096
#endif

/* The folder part of path ("." when it has none) into dir. */
static int
folder_of(const char* path, char* dir, size_t cap)
{
  const char* slash = strrchr(path, '/');
  if (!slash)
    return snprintf(dir, cap, ".") < (int)cap ? 0 : -1;
  const size_t len = slash == path ? 1 : (size_t)(slash - path);
  if (len + 1 > cap)
    return -1;
  memcpy(dir, path, len);
  dir[len] = '\0';
  return 0;
}

int
dacpo_temp_sibling(const char* path, const char* tag, long id, char* buf, size_t cap)
{
  if (cap > 0)
    buf[0] = '\0';
  if (!path || !tag || !buf || !*path)
    return -1;
  const char* slash = strrchr(path, '/');
  const char* name = slash ? slash + 1 : path;
  const size_t dir_len = slash ? (size_t)(slash - path) + 1 : 0;
  /* the target's extension at the end: writers that choose the format by the
     name (PCL's) write the right one */
  const char* dot = strrchr(name, '.');
  const char* ext = dot && dot != name && strlen(dot) <= 8 ? dot : "";
  char tail[64];
  const int tl = snprintf(tail, sizeof(tail), ".%s%ld%s", tag, id, ext);
  const size_t name_len = 1 + strlen(name) + (size_t)tl;
  const size_t total = dir_len + name_len;
  if (!*name || tl <= 0 || name_len > NAME_MAX || total + 1 > PATH_MAX || total + 1 > cap)
    return -1;
  snprintf(buf, cap, "%.*s.%s%s", (int)dir_len, path, name, tail);
  return 0;
}

int
dacpo_output_path_check(const char* path, char* err, size_t errlen)
{
  char dir[PATH_MAX];
  char tmp[PATH_MAX];
  struct stat st;
  if (!path || !*path) {
    dacpo_support_err(err, errlen, "empty output path");
    return -1;
  }
  if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
    dacpo_support_err(err, errlen, "'%s' is a folder, not a file name", path);
    return -1;
  }
  if (dacpo_temp_sibling(path, "tmp", (long)getpid(), tmp, sizeof(tmp)) != 0 ||
      folder_of(path, dir, sizeof(dir)) != 0) {
    dacpo_support_err(
        err, errlen, "'%s': name too long for a temporary file beside it", path);
    return -1;
  }
  if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode)) {
    dacpo_support_err(err, errlen, "cannot write '%s': folder '%s' does not exist", path, dir);
    return -1;
  }
  if (access(dir, W_OK) != 0) {
    dacpo_support_err(
        err, errlen, "cannot write '%s': folder '%s' is not writable (%s)", path, dir,
        strerror(errno));
    return -1;
  }
  return 0;
}
