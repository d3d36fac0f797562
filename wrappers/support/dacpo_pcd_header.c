/* SPDX-License-Identifier: BSD-3-Clause */
/* The PCD header parser (dacpo_pcd_read_header, see dacpo_pcd.h): the header
 * read line by line up to DATA, every line checked, the fields laid out. Used
 * by dacpo_pcd_read() and by the pcl_dacpo_* tools' file checks, so a PCD
 * header is parsed by this code alone. */
#include "dacpo_pcd.h"
#include "dacpo_support_err.h"

#include <ctype.h>
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#define PCD_MAX_LINE 4096 /* longer lines are read cut to this */

/* Strict unsigned number of a header value. */
static int
parse_count(const char* s, size_t* out)
{
  if (!s || !isdigit((unsigned char)*s))
    return 0;
  errno = 0;
  char* end = NULL;
  unsigned long long v = strtoull(s, &end, 10);
  if (errno || *end != '\0')
    return 0;
  *out = (size_t)v;
  return 1;
}

/* Splits line in place at spaces, tabs and CRs into at most max tokens;
 * returns their number. */
static int
tokens(char* line, char** tok, int max)
{
  int m = 0;
  char* s = line;
  while (m < max) {
    s += strspn(s, " \t\r");
    if (!*s)
      break;
    tok[m++] = s;
    s += strcspn(s, " \t\r");
    if (*s)
      *s++ = '\0';
  }
  return m;
}

/* One header line without its '\n', cut to cap - 1 bytes (the rest of a
 * longer line is skipped): 0; -1 at the end of the file with nothing read;
 * -3 when it holds a NUL byte. */
static int
read_line(FILE* fp, char* line, size_t cap)
{
  size_t k = 0;
  int c, nul = 0;
  while ((c = getc(fp)) != EOF && c != '\n') {
    nul |= c == '\0';
    if (k + 1 < cap)
      line[k++] = (char)c;
  }
  line[k] = '\0';
  if (c == EOF && k == 0 && !nul)
    return -1;
  return nul ? -3 : 0;
}

/* A SIZE, TYPE or COUNT line: one value per field (val[0..nv)). */
static int
field_values(dacpo_pcd_header* h,
             const char* key,
             char** val,
             int nv,
             const char* path,
             char* err,
             size_t errlen)
{
  if (nv != h->nf) {
    dacpo_support_file_err(err,
                           errlen,
                           path,
                           "PCD",
                           h->lines,
                           "%s has %d values for %d fields",
                           key,
                           nv,
                           h->nf);
    return 0;
  }
  for (int i = 0; i < h->nf; ++i) {
    const char* v = val[i];
    size_t x = 0;
    if (key[0] == 'T') {
      if (strlen(v) != 1 || !strchr("IUF", v[0])) {
        dacpo_support_file_err(
            err, errlen, path, "PCD", h->lines, "TYPE '%s' is not I, U or F", v);
        return 0;
      }
      h->f[i].type = v[0];
    }
    else if (!parse_count(v, &x) || x == 0 || x > (key[0] == 'S' ? 8u : 1000000u) ||
             (key[0] == 'S' && x != 1 && x != 2 && x != 4 && x != 8)) {
      dacpo_support_file_err(err, errlen, path, "PCD", h->lines, "bad %s '%s'", key, v);
      return 0;
    }
    else if (key[0] == 'S')
      h->f[i].size = (int)x;
    else
      h->f[i].count = x;
  }
  h->have_size |= key[0] == 'S';
  h->have_type |= key[0] == 'T';
  return 1;
}

/* A FIELDS (or COLUMNS) line of m - 1 names: a (repeated) field list needs
 * its SIZE and TYPE lines after it, the sizes of an earlier list do not carry
 * over. */
static void
field_names(dacpo_pcd_header* h, char** tok, int m)
{
  h->nf = m - 1;
  h->have_size = h->have_type = 0;
  for (int i = 0; i < h->nf; ++i) {
    snprintf(h->f[i].name, sizeof(h->f[i].name), "%s", tok[i + 1]);
    h->f[i].count = 1;
    h->f[i].size = 0;
    h->f[i].type = 0;
  }
}

/* WIDTH, HEIGHT or POINTS with its count: 1; 0 for another key. */
static int
size_line(dacpo_pcd_header* h, char** tok, int m, int* ok)
{
  const char* key = tok[0];
  size_t* target = !strcmp(key, "WIDTH")    ? &h->width
                   : !strcmp(key, "HEIGHT") ? &h->height
                   : !strcmp(key, "POINTS") ? &h->points
                                            : NULL;
  if (!target)
    return 0;
  *ok = m == 2 && parse_count(tok[1], target);
  h->have_width |= *ok && target == &h->width;
  h->have_height |= *ok && target == &h->height;
  h->have_points |= *ok && target == &h->points;
  return 1;
}

/* One header line (already without its newline) into h. */
static int
header_line(dacpo_pcd_header* h, char* line, const char* path, char* err, size_t errlen)
{
  char* tok[DACPO_PCD_MAX_FIELDS + 2];
  const int m = tokens(line, tok, DACPO_PCD_MAX_FIELDS + 2);
  if (m == 0 || tok[0][0] == '#')
    return 1;
  const char* key = tok[0];
  int ok = 1;
  if (m > DACPO_PCD_MAX_FIELDS + 1) {
    dacpo_support_file_err(err,
                           errlen,
                           path,
                           "PCD",
                           h->lines,
                           "more than %d values",
                           DACPO_PCD_MAX_FIELDS);
    return 0;
  }
  if (!strcmp(key, "VERSION") || !strcmp(key, "VIEWPOINT"))
    return 1;
  if (!strcmp(key, "FIELDS") || !strcmp(key, "COLUMNS")) {
    field_names(h, tok, m);
    return 1;
  }
  if (!strcmp(key, "SIZE") || !strcmp(key, "TYPE") || !strcmp(key, "COUNT"))
    return field_values(h, key, tok + 1, m - 1, path, err, errlen);
  if (size_line(h, tok, m, &ok)) {
    if (!ok)
      dacpo_support_file_err(err, errlen, path, "PCD", h->lines, "bad %s", key);
    return ok;
  }
  if (!strcmp(key, "DATA")) {
    snprintf(h->data, sizeof(h->data), "%s", m > 1 ? tok[1] : "");
    return 1;
  }
  dacpo_support_file_err(err,
                         errlen,
                         path,
                         "PCD",
                         h->lines,
                         "unknown keyword '%s' (not a PCD file?)",
                         key);
  return 0;
}

/* The first line that is not blank starts a PCD file: a comment, VERSION or
 * FIELDS (what every PCD writer puts first). */
static int
starts_pcd(const char* line, int* started)
{
  const char* p = line + strspn(line, " \t\r");
  if (*started || !*p)
    return 1;
  *started = 1;
  return *p == '#' || !strncmp(p, "VERSION", 7) || !strncmp(p, "FIELDS", 6);
}

/* The next line of the header into h; 0 with the error in err. */
static int
next_line(FILE* fp,
          dacpo_pcd_header* h,
          int* started,
          const char* path,
          char* err,
          size_t errlen)
{
  char line[PCD_MAX_LINE];
  const int rc = read_line(fp, line, sizeof(line));
  if (rc == -1) {
    dacpo_support_file_err(
        err, errlen, path, "PCD", h->lines, "no DATA line: the header ends first");
    return 0;
  }
  ++h->lines;
  if (rc == -3) {
    dacpo_support_file_err(
        err, errlen, path, "PCD", h->lines, "binary bytes in the header");
    return 0;
  }
  if (!starts_pcd(line, started)) {
    dacpo_support_file_err(err,
                           errlen,
                           path,
                           "PCD",
                           h->lines,
                           "unexpected '%.60s' (not a PCD file?)",
                           line + strspn(line, " \t\r"));
    return 0;
  }
  return header_line(h, line, path, err, errlen);
}

int
dacpo_pcd_read_header(
    FILE* fp, const char* path, dacpo_pcd_header* h, char* err, size_t errlen)
{
  if (!fp || !path || !h) {
    dacpo_support_err(err, errlen, "dacpo_pcd_read_header: NULL argument");
    return DACPO_PLY_ERR_ARGUMENT;
  }
  int started = 0;
  memset(h, 0, sizeof(*h));
  while (!h->data[0])
    if (!next_line(fp, h, &started, path, err, errlen))
      return DACPO_PLY_ERR_FORMAT;
  if (strcmp(h->data, "binary") && strcmp(h->data, "ascii") &&
      strcmp(h->data, "binary_compressed")) {
    dacpo_support_file_err(
        err, errlen, path, "PCD", h->lines, "unknown DATA '%s'", h->data);
    return DACPO_PLY_ERR_FORMAT;
  }
  if (h->nf == 0 || !h->have_size || !h->have_type) {
    dacpo_support_file_err(
        err, errlen, path, "PCD", h->lines, "FIELDS, SIZE and TYPE are required");
    return DACPO_PLY_ERR_FORMAT;
  }
  for (int i = 0; i < h->nf; ++i) {
    h->f[i].offset = h->record;
    h->record += (size_t)h->f[i].size * h->f[i].count;
  }
  return DACPO_PLY_OK;
}
