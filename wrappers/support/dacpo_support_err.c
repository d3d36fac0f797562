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
