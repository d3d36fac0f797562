/* SPDX-License-Identifier: BSD-3-Clause */
#define _POSIX_C_SOURCE 200809L
#include "dacpo_cleanup.h"

#include <signal.h>
#include <string.h>
#include <unistd.h>

#define SLOTS 16
#define PATH_CAP 4352

typedef struct slot {
  volatile sig_atomic_t used; /* set after path is complete, cleared first */
  size_t series;              /* 0: one file; n: "<path>.tile0" .. n - 1 */
  char path[PATH_CAP];
} slot;

static slot g_slots[SLOTS];
static volatile sig_atomic_t g_installed;

/* "<prefix>.tile<i>" into buf with no stdio (the handler may not use it). */
static void
tile_name(const char* prefix, size_t i, char* buf, size_t cap)
{
  char digits[24];
  size_t nd = 0, len = strlen(prefix);
  do {
    digits[nd++] = (char)('0' + i % 10);
    i /= 10;
  } while (i > 0 && nd < sizeof(digits));
  if (len + 5 + nd + 1 > cap)
    return;
  memcpy(buf, prefix, len);
  memcpy(buf + len, ".tile", 5);
  len += 5;
  while (nd > 0)
    buf[len++] = digits[--nd];
  buf[len] = '\0';
}

static void
on_signal(int sig)
{
  char name[PATH_CAP + 32];
  for (int s = 0; s < SLOTS; ++s) {
    if (!g_slots[s].used)
      continue;
    if (g_slots[s].series == 0)
      unlink(g_slots[s].path);
    for (size_t i = 0; i < g_slots[s].series; ++i) {
      name[0] = '\0';
      tile_name(g_slots[s].path, i, name, sizeof(name));
      if (name[0])
        unlink(name);
    }
  }
  signal(sig, SIG_DFL);
  raise(sig);
}

int
dacpo_cleanup_install(void)
{
  if (g_installed)
    return 0;
  struct sigaction sa;
  memset(&sa, 0, sizeof(sa));
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  const int sigs[3] = {SIGINT, SIGTERM, SIGHUP};
  for (int i = 0; i < 3; ++i)
    sigaddset(&sa.sa_mask, sigs[i]);
  for (int i = 0; i < 3; ++i) {
    struct sigaction old;
    /* a signal the caller ignores (nohup) stays ignored */
    if (sigaction(sigs[i], NULL, &old) == 0 && old.sa_handler == SIG_IGN)
      continue;
    if (sigaction(sigs[i], &sa, NULL) != 0)
      return -1;
  }
  g_installed = 1;
  return 0;
}

static int
add(const char* path, size_t series)
{
  if (!path || strlen(path) + 1 > PATH_CAP)
    return -1;
  for (int s = 0; s < SLOTS; ++s)
    if (!g_slots[s].used) {
      memcpy(g_slots[s].path, path, strlen(path) + 1);
      g_slots[s].series = series;
      g_slots[s].used = 1;
      return s;
    }
  return -1;
}

int
dacpo_cleanup_add(const char* path)
{
  return add(path, 0);
}

int
dacpo_cleanup_add_series(const char* prefix, size_t count)
{
  return count > 0 ? add(prefix, count) : -1;
}

void
dacpo_cleanup_drop(int slot)
{
  if (slot >= 0 && slot < SLOTS)
    g_slots[slot].used = 0;
}
