/* SPDX-License-Identifier: BSD-3-Clause */
/* Private to the PLY reader (dacpo_ply.c, dacpo_ply_header.c,
 * dacpo_ply_rows.c): the buffered input, the header model and the helpers
 * these files share. Not part of dacpo_ply.h. */
#ifndef DACPO_PLY_INTERNAL_H
#define DACPO_PLY_INTERNAL_H

#include "dacpo_ply.h"

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#define PLY_MAX_ELEMENTS DACPO_PLY_MAX_ELEMENTS
#define PLY_MAX_PROPS DACPO_PLY_MAX_PROPERTIES
#define PLY_BUF_SIZE 65536

/* ------------------------------------------------------------------------- */
/* Buffered input.                                                            */

typedef struct ply_in {
  FILE* f;
  unsigned char* buf;
  size_t pos, len;
  size_t consumed; /* bytes handed out so far (header included) */
  int eof;
  int eol; /* ASCII: the last token ended its line */
} ply_in;

/* ------------------------------------------------------------------------- */
/* Header model.                                                              */

typedef enum ply_type {
  T_NONE = 0,
  T_I8,
  T_U8,
  T_I16,
  T_U16,
  T_I32,
  T_U32,
  T_F32,
  T_F64
} ply_type;

typedef struct ply_prop {
  ply_type type;       /* scalar type, or the item type of a list */
  ply_type count_type; /* T_NONE for scalars */
  int role;            /* 0..5 = x y z nx ny nz, -1 other */
} ply_prop;

typedef struct ply_element {
  char name[64];
  uint64_t count;
  ply_prop props[PLY_MAX_PROPS];
  int nprops;
} ply_element;

enum { FMT_ASCII, FMT_BLE, FMT_BBE };

typedef struct ply_header {
  int format;
  ply_element* el; /* PLY_MAX_ELEMENTS */
  int nel;
  int lines; /* header lines read: end_header's line, or the line of an error */
} ply_header;

/* Bytes of one value of type t (0 for T_NONE). */
size_t
dacpo_ply_type_size(ply_type t);

/* 1 when a value of type t converts to float exactly. */
int
dacpo_ply_exact_in_float(ply_type t);

/* Decode one binary value of type t at p (swap = file is big-endian). */
double
dacpo_ply_decode(const unsigned char* p, ply_type t, int swap);

/* One header line without its terminator ("\n" or "\r\n"; none for the last
 * line of the file) from in, cut to cap - 1 bytes: 0, -1 at the end of the
 * file, -3 when it holds a NUL byte. */
int
dacpo_ply_in_line(ply_in* in, char* line, size_t cap);

/* The header from the start of in through end_header into h (h->el holds
 * PLY_MAX_ELEMENTS); errors name path and the line (dacpo_ply_header.c). */
int
dacpo_ply_parse_header(
    ply_in* in, ply_header* h, const char* path, char* err, size_t errlen);

/* Opens path and reads up to its first vertex row (see dacpo_ply.c); release
 * with dacpo_ply_close() whatever it returns. */
int
dacpo_ply_open_vertices(const char* path,
                        ply_in* in,
                        ply_header* h,
                        ply_element** vert,
                        int* has_normals,
                        char* err,
                        size_t errlen);

void
dacpo_ply_close(ply_in* in, ply_header* h);

#endif /* DACPO_PLY_INTERNAL_H */
