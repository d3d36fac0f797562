/* SPDX-License-Identifier: BSD-3-Clause */
#include "dacpo_support_err.h"

#include <stdarg.h>
#include <stdio.h>

void
dacpo_support_err(char* err, size_t errlen, const char* fmt, ...)
{
  va_list ap;
  if (!err || errlen == 0)
    return;
  va_start(ap, fmt);
  vsnprintf(err, errlen, fmt, ap);
  va_end(ap);
}

void
dacpo_support_file_err(char* err,
                       size_t errlen,
                       const char* path,
                       const char* kind,
                       long line,
                       const char* fmt,
                       ...)
{
  va_list ap;
  va_start(ap, fmt);
  dacpo_support_file_verr(err, errlen, path, kind, line, fmt, ap);
  va_end(ap);
}

void
dacpo_support_file_verr(char* err,
                        size_t errlen,
                        const char* path,
                        const char* kind,
                        long line,
                        const char* fmt,
                        va_list ap)
{
  char what[512];
  if (!err || errlen == 0)
    return;
  vsnprintf(what, sizeof(what), fmt, ap);
  for (char* c = what; *c; ++c)
    if ((unsigned char)*c < 32 || (unsigned char)*c > 126)
      *c = '?';
  snprintf(
      err, errlen, "'%s' is not a valid %s file: line %ld: %s", path, kind, line, what);
}
