/* SPDX-License-Identifier: BSD-3-Clause */
/* The error text of the support library (PLY I/O, scenes): printf-style into
 * the caller's buffer, nothing when err is NULL or errlen is 0. Private to
 * wrappers/support. */
#ifndef DACPO_SUPPORT_ERR_H
#define DACPO_SUPPORT_ERR_H

#include <stdarg.h>
#include <stddef.h>

#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
void
dacpo_support_err(char* err, size_t errlen, const char* fmt, ...);

/* The error of a file that breaks its format, the same for every reader and
 * check: "'path' is not a valid KIND file: line N: what", the what's bytes
 * outside printable ASCII shown as '?'. */
#if defined(__GNUC__)
__attribute__((format(printf, 6, 7)))
#endif
void
dacpo_support_file_err(char* err,
                       size_t errlen,
                       const char* path,
                       const char* kind,
                       long line,
                       const char* fmt,
                       ...);

/* dacpo_support_file_err with the arguments in a va_list (for helpers that
 * add their own context). */
void
dacpo_support_file_verr(char* err,
                        size_t errlen,
                        const char* path,
                        const char* kind,
                        long line,
                        const char* fmt,
                        va_list ap);

#endif /* DACPO_SUPPORT_ERR_H */
