/* SPDX-License-Identifier: BSD-3-Clause */
/* The PLY header parser: the header read line by line up to end_header,
 * every line checked (dacpo_ply_parse_header, for the reader in dacpo_ply.c),
 * and the public views of it for the pcl_dacpo_* tools' file checks
 * (dacpo_ply_read_header, dacpo_ply_binary_size in dacpo_ply.h). */
#define _FILE_OFFSET_BITS 64
#define _POSIX_C_SOURCE 200809L
#include "dacpo_ply.h"
#include "dacpo_ply_internal.h"
#include "dacpo_support_err.h"
#include <sys/types.h>

#include <errno.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PLY_MAX_LINE 4096 /* longer lines are read cut to this */
#define PLY_MAX_HEADER_LINES 4096

/* Where the parse stands: the file (for messages), the line, the message. */
typedef struct ply_parse {
  const char* path;
  int line;
  char* err;
  size_t errlen;
} ply_parse;

/* The parse's error at its current line; returns DACPO_PLY_ERR_FORMAT. */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static int
ply_bad(const ply_parse* ps, const char* fmt, ...)
{
  va_list ap;
  va_start(ap, fmt);
  dacpo_support_file_verr(ps->err, ps->errlen, ps->path, "PLY", ps->line, fmt, ap);
  va_end(ap);
  return DACPO_PLY_ERR_FORMAT;
}

static ply_type
parse_type(const char* s)
{
  static const struct {
    const char* name;
    ply_type type;
  } names[] = {{"char", T_I8},
               {"int8", T_I8},
               {"uchar", T_U8},
               {"uint8", T_U8},
               {"short", T_I16},
               {"int16", T_I16},
               {"ushort", T_U16},
               {"uint16", T_U16},
               {"int", T_I32},
               {"int32", T_I32},
               {"uint", T_U32},
               {"uint32", T_U32},
               {"float", T_F32},
               {"float32", T_F32},
               {"double", T_F64},
               {"float64", T_F64}};
  for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); ++i)
    if (strcmp(s, names[i].name) == 0)
      return names[i].type;
  return T_NONE;
}

double
dacpo_ply_decode_named(const unsigned char* p, const char* type_name, int big_endian)
{
  const ply_type t = parse_type(type_name);
  return t == T_NONE ? 0.0 : dacpo_ply_decode(p, t, big_endian != 0);
}

static int
prop_role(const char* name)
{
  static const char* const roles[6] = {"x", "y", "z", "nx", "ny", "nz"};
  for (int i = 0; i < 6; ++i)
    if (strcmp(name, roles[i]) == 0)
      return i;
  return -1;
}

/* Parse an unsigned decimal count; -1 on anything else. */
static int
parse_count(const char* s, uint64_t* out)
{
  char* end;
  unsigned long long v;
  if (!s || *s < '0' || *s > '9')
    return -1;
  errno = 0;
  v = strtoull(s, &end, 10);
  if (errno != 0 || *end != '\0')
    return -1;
  *out = (uint64_t)v;
  return 0;
}

/* Split s in place at spaces and tabs; at most max words (the rest is ignored,
 * extra words only make a line invalid through the callers' count checks). */
static int
split_words(char* s, char** words, int max)
{
  int n = 0;
  while (*s) {
    while (*s == ' ' || *s == '\t')
      *s++ = '\0';
    if (!*s)
      break;
    if (n == max)
      return n + 1;
    words[n++] = s;
    while (*s && *s != ' ' && *s != '\t')
      ++s;
  }
  return n;
}

/* A "format" line: ascii, binary_little_endian or binary_big_endian. */
static int
header_format(ply_header* h, char** tok, int nt, ply_parse* ps)
{
  if (nt < 2 || (strcmp(tok[1], "ascii") && strcmp(tok[1], "binary_little_endian") &&
                 strcmp(tok[1], "binary_big_endian"))) {
    return ply_bad(
        ps,
        "unsupported format '%s' (ascii, binary_little_endian or binary_big_endian)",
        nt > 1 ? tok[1] : "");
  }
  h->format = strcmp(tok[1], "ascii") == 0                  ? FMT_ASCII
              : strcmp(tok[1], "binary_little_endian") == 0 ? FMT_BLE
                                                            : FMT_BBE;
  return DACPO_PLY_OK;
}

/* An "element name count" line: a new element. */
static int
header_element(ply_header* h, char** tok, int nt, ply_parse* ps)
{
  ply_element* e;
  if (nt != 3) {
    return ply_bad(ps, "'element NAME COUNT' expected");
  }
  if (h->nel >= PLY_MAX_ELEMENTS) {
    return ply_bad(ps, "more than %d elements", PLY_MAX_ELEMENTS);
  }
  e = &h->el[h->nel++];
  memset(e, 0, sizeof(*e));
  snprintf(e->name, sizeof(e->name), "%s", tok[1]);
  if (parse_count(tok[2], &e->count) != 0) {
    return ply_bad(ps, "bad count '%s' for element '%s'", tok[2], e->name);
  }
  return DACPO_PLY_OK;
}

/* The types of a "property type name" or "property list count_type type
 * name" line into p; 0 with the reason in *why when they are bad. */
static int
property_types(ply_prop* p, char** tok, int nt, const char** why)
{
  if (nt == 5 && strcmp(tok[1], "list") == 0) {
    p->count_type = parse_type(tok[2]);
    p->type = parse_type(tok[3]);
    p->role = -1;
    *why = "bad list property types";
    return p->count_type != T_NONE && p->count_type != T_F32 &&
           p->count_type != T_F64 && p->type != T_NONE;
  }
  if (nt == 3) {
    p->count_type = T_NONE;
    p->type = parse_type(tok[1]);
    p->role = prop_role(tok[2]);
    *why = "unknown property type";
    return p->type != T_NONE;
  }
  *why = "bad property line";
  return 0;
}

/* A property line: a property of the last element. */
static int
header_property(ply_header* h, char** tok, int nt, ply_parse* ps)
{
  ply_element* e = h->nel > 0 ? &h->el[h->nel - 1] : NULL;
  const char* why = NULL;
  if (!e) {
    return ply_bad(ps, "a property before any element");
  }
  if (e->nprops >= PLY_MAX_PROPS) {
    return ply_bad(
        ps, "more than %d properties in element '%s'", PLY_MAX_PROPS, e->name);
  }
  if (!property_types(&e->props[e->nprops], tok, nt, &why)) {
    return ply_bad(ps, "%s", why);
  }
  e->nprops++;
  return DACPO_PLY_OK;
}

/* One header line after the first (split in place): DACPO_PLY_OK, or 1 at
 * end_header, or an error. */
static int
header_line(ply_header* h, char* line, int* have_format, ply_parse* ps)
{
  char* tok[6] = {NULL, NULL, NULL, NULL, NULL, NULL};
  const int nt = split_words(line, tok, 6);
  if (nt == 0 || strcmp(tok[0], "comment") == 0 || strcmp(tok[0], "obj_info") == 0)
    return DACPO_PLY_OK;
  if (strcmp(tok[0], "end_header") == 0) {
    if (*have_format)
      return 1;
    return ply_bad(ps, "no format line");
  }
  if (strcmp(tok[0], "format") == 0) {
    *have_format = 1;
    return header_format(h, tok, nt, ps);
  }
  if (strcmp(tok[0], "element") == 0)
    return header_element(h, tok, nt, ps);
  if (strcmp(tok[0], "property") == 0)
    return header_property(h, tok, nt, ps);
  return ply_bad(ps, "unknown keyword '%s'", tok[0]);
}

/* The first line: "ply" alone (blanks around it allowed). */
static int
first_line(ply_in* in, const char* path, char* err, size_t errlen)
{
  char line[PLY_MAX_LINE];
  char* tok[2] = {NULL, NULL};
  const int rc = dacpo_ply_in_line(in, line, sizeof(line));
  if (rc == -3)
    dacpo_support_file_err(err, errlen, path, "PLY", 1, "binary bytes in the header");
  else if (rc != 0 || split_words(line, tok, 1) != 1 || strcmp(tok[0], "ply") != 0)
    dacpo_support_file_err(
        err, errlen, path, "PLY", 1, "the file does not start with 'ply'");
  else
    return DACPO_PLY_OK;
  return DACPO_PLY_ERR_FORMAT;
}

int
dacpo_ply_parse_header(
    ply_in* in, ply_header* h, const char* path, char* err, size_t errlen)
{
  char line[PLY_MAX_LINE];
  int have_format = 0;
  ply_parse ps = {path, 1, err, errlen};
  h->lines = 1;
  if (first_line(in, path, err, errlen) != DACPO_PLY_OK)
    return DACPO_PLY_ERR_FORMAT;
  for (ps.line = 2; ps.line < PLY_MAX_HEADER_LINES; ++ps.line) {
    const int rc = dacpo_ply_in_line(in, line, sizeof(line));
    h->lines = ps.line;
    if (rc == -1) {
      h->lines = ps.line - 1;
      dacpo_support_file_err(
          err, errlen, path, "PLY", h->lines, "the header ends before 'end_header'");
      return DACPO_PLY_ERR_FORMAT;
    }
    if (rc == -3) {
      dacpo_support_file_err(
          err, errlen, path, "PLY", ps.line, "binary bytes in the header");
      return DACPO_PLY_ERR_FORMAT;
    }
    const int status = header_line(h, line, &have_format, &ps);
    if (status != DACPO_PLY_OK)
      return status == 1 ? DACPO_PLY_OK : status;
  }
  dacpo_support_file_err(err,
                         errlen,
                         path,
                         "PLY",
                         ps.line,
                         "the header is longer than %d lines",
                         PLY_MAX_HEADER_LINES);
  return DACPO_PLY_ERR_FORMAT;
}

/* ------------------------------------------------------------------------- */
/* Public views.                                                              */

/* The internal header as dacpo_ply_header_info. */
static void
header_info(const ply_header* h, dacpo_ply_header_info* info)
{
  info->format = h->format == FMT_ASCII ? DACPO_PLY_ASCII
                 : h->format == FMT_BLE ? DACPO_PLY_BINARY_LE
                                        : DACPO_PLY_BINARY_BE;
  info->nelements = h->nel;
  for (int i = 0; i < h->nel; ++i) {
    dacpo_ply_element_info* e = &info->elements[i];
    memcpy(e->name, h->el[i].name, sizeof(e->name));
    e->count = h->el[i].count;
    e->nprops = h->el[i].nprops;
    for (int j = 0; j < e->nprops; ++j) {
      e->props[j].bytes = (unsigned char)dacpo_ply_type_size(h->el[i].props[j].type);
      e->props[j].count_bytes =
          (unsigned char)dacpo_ply_type_size(h->el[i].props[j].count_type);
    }
  }
}

/* The buffers of a parse over f (release with dacpo_ply_close, f stays open). */
static int
parse_file(
    FILE* f, ply_in* in, ply_header* h, const char* path, char* err, size_t errlen)
{
  memset(in, 0, sizeof(*in));
  memset(h, 0, sizeof(*h));
  in->buf = (unsigned char*)malloc(PLY_BUF_SIZE);
  h->el = (ply_element*)malloc(PLY_MAX_ELEMENTS * sizeof(ply_element));
  if (!in->buf || !h->el) {
    dacpo_support_err(err, errlen, "out of memory");
    return DACPO_PLY_ERR_MEMORY;
  }
  in->f = f;
  return dacpo_ply_parse_header(in, h, path, err, errlen);
}

int
dacpo_ply_read_header(
    FILE* f, const char* path, dacpo_ply_header_info* info, char* err, size_t errlen)
{
  ply_in in;
  ply_header h;
  if (!f || !path || !info) {
    dacpo_support_err(err, errlen, "dacpo_ply_read_header: NULL argument");
    return DACPO_PLY_ERR_ARGUMENT;
  }
  memset(info, 0, sizeof(*info));
  const off_t start = ftello(f);
  int status = start < 0 ? DACPO_PLY_ERR_IO : parse_file(f, &in, &h, path, err, errlen);
  if (start < 0)
    dacpo_support_err(err, errlen, "cannot tell the position in '%s'", path);
  else
    info->lines = h.lines;
  if (status == DACPO_PLY_OK) {
    header_info(&h, info);
    info->data_offset = (unsigned long long)start + in.consumed;
    if (fseeko(f, (off_t)info->data_offset, SEEK_SET) != 0) {
      dacpo_support_err(err, errlen, "cannot seek in '%s'", path);
      status = DACPO_PLY_ERR_IO;
    }
  }
  if (start >= 0) {
    in.f = NULL; /* the caller's */
    dacpo_ply_close(&in, &h);
  }
  return status;
}

/* Bytes of the rows of element e of a binary file, f at its first row: count
 * x record for rows of scalars; rows with lists are walked count by count.
 * -1 when the data ends first or a count is malformed. */
static int
element_bytes(FILE* f, const ply_element* e, int swap, unsigned long long* bytes)
{
  unsigned long long record = 0;
  int lists = 0;
  for (int j = 0; j < e->nprops; ++j) {
    record +=
        e->props[j].count_type != T_NONE ? 0 : dacpo_ply_type_size(e->props[j].type);
    lists |= e->props[j].count_type != T_NONE;
  }
  if (!lists) {
    *bytes = e->count * record;
    return record > 0 && e->count > UINT64_MAX / record ? -1 : 0;
  }
  *bytes = 0;
  for (uint64_t r = 0; r < e->count; ++r)
    for (int j = 0; j < e->nprops; ++j) {
      const ply_prop* p = &e->props[j];
      const size_t cb = dacpo_ply_type_size(p->count_type),
                   ib = dacpo_ply_type_size(p->type);
      double n = 1.0;
      unsigned char c[8];
      if (cb > 0) {
        if (fread(c, 1, cb, f) != cb)
          return -1;
        n = dacpo_ply_decode(c, p->count_type, swap);
        if (!(n >= 0.0) || n > 4294967295.0)
          return -1;
        *bytes += cb;
      }
      if (fseeko(f, (off_t)((uint64_t)n * ib), SEEK_CUR) != 0)
        return -1;
      *bytes += (uint64_t)n * ib;
    }
  return 0;
}

int
dacpo_ply_binary_size(const char* path,
                      unsigned long long* bytes,
                      char* err,
                      size_t errlen)
{
  ply_in in;
  ply_header h;
  FILE* f = path && bytes ? fopen(path, "rb") : NULL;
  if (!f) {
    dacpo_support_err(
        err, errlen, "cannot open '%s': %s", path ? path : "", strerror(errno));
    return DACPO_PLY_ERR_IO;
  }
  int status = parse_file(f, &in, &h, path, err, errlen);
  if (status == DACPO_PLY_OK && h.format == FMT_ASCII) {
    dacpo_support_err(err, errlen, "'%s' is ASCII PLY", path);
    status = DACPO_PLY_ERR_FORMAT;
  }
  unsigned long long total = in.consumed;
  for (int i = 0; status == DACPO_PLY_OK && i < h.nel; ++i) {
    unsigned long long b = 0;
    if (fseeko(f, (off_t)total, SEEK_SET) != 0 ||
        element_bytes(f, &h.el[i], h.format == FMT_BBE, &b) != 0 ||
        b > UINT64_MAX - total) {
      dacpo_support_err(
          err, errlen, "'%s': the rows of element '%s' end early", path, h.el[i].name);
      status = DACPO_PLY_ERR_FORMAT;
    }
    total += b;
  }
  *bytes = status == DACPO_PLY_OK ? total : 0;
  dacpo_ply_close(&in, &h); /* closes f */
  return status;
}
