// SPDX-License-Identifier: BSD-3-Clause
// Out of memory, everywhere: a small but complete run (two blocks, iPSR, VCR
// weights, the 0-1 program, the kept mesh, estimated normals) is repeated with
// its 1st, 2nd, ... allocation failing (this executable's malloc / calloc /
// realloc, which the core and lp_solve call, fail on request). Every run must
// return a clean status with a message, never crash, and leave the caller's
// normals exactly as they were unless it succeeded ("normals are written only
// on success", dacpo.h). glibc only (__libc_malloc).
#include <dacpo/dacpo.h>

#include <gtest/gtest.h>

#include "dacpo_scene.h"

#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void*
__libc_realloc(void*, size_t);
}

namespace {
// Armed: count allocations, fail number fail_at (1-based). Single-threaded
// runs only (num_threads = 1), so plain globals suffice.
bool g_armed = false;
long g_count = 0;
long g_fail_at = 0;

bool
failNow()
{
  if (!g_armed)
    return false;
  ++g_count;
  return g_count == g_fail_at;
}
} // namespace

extern "C" void*
malloc(size_t n)
{
  return failNow() ? nullptr : __libc_malloc(n);
}

extern "C" void*
calloc(size_t a, size_t b)
{
  return failNow() ? nullptr : __libc_calloc(a, b);
}

extern "C" void*
realloc(void* p, size_t n)
{
  return failNow() ? nullptr : __libc_realloc(p, n);
}

namespace {

struct Outcome {
  dacpo_status status;
  std::string error;
  std::vector<float> normals;
};

Outcome
orientOnce(const dacpo_scene& sc,
           const std::vector<float>& input,
           long fail_at,
           long* count)
{
  dacpo_ctx* ctx = nullptr;
  Outcome r{DACPO_ERR_INTERNAL, "", input};
  if (dacpo_ctx_create(&ctx) != DACPO_OK)
    return r;
  dacpo_params p;
  dacpo_params_init(&p);
  p.estimate_normals = 1;
  p.num_blocks = 2;
  p.num_threads = 1;
  p.keep_mesh = 1;
  p.vcr_image_size = 32;
  g_count = 0;
  g_fail_at = fail_at;
  g_armed = true;
  r.status = dacpo_orient(ctx, &p, nullptr, nullptr, sc.xyz, r.normals.data(), sc.n);
  g_armed = false;
  *count = g_count;
  r.error = dacpo_ctx_last_error(ctx);
  dacpo_ctx_free(ctx);
  return r;
}

} // namespace

TEST(AllocationFailures, EveryFailureIsCleanAndLeavesTheNormalsUntouched)
{
  dacpo_scene_params sp;
  dacpo_scene_params_init(&sp);
  sp.kind = DACPO_SCENE_BOX_OPEN;
  sp.target_points = 400;
  dacpo_scene sc;
  char err[256] = "";
  ASSERT_EQ(dacpo_scene_generate(&sp, &sc, err, sizeof(err)), 0) << err;
  // a recognisable input: the ground truth, so a partial write would show
  const std::vector<float> input(sc.normals, sc.normals + 3 * sc.n);

  long total = 0;
  const Outcome clean = orientOnce(sc, input, 0, &total);
  ASSERT_EQ(clean.status, DACPO_OK) << clean.error;
  ASSERT_GT(total, 100) << "the run should allocate (is malloc interposed?)";
  RecordProperty("allocations", std::to_string(total));

  long failed = 0;
  for (long k = 1; k <= total; ++k) {
    long seen = 0;
    const Outcome r = orientOnce(sc, input, k, &seen);
    if (r.status == DACPO_OK) {
      // an allocation whose failure has a fallback (e.g. an optional buffer)
      EXPECT_EQ(r.normals, clean.normals) << "allocation " << k;
      continue;
    }
    ++failed;
    EXPECT_FALSE(r.error.empty()) << "allocation " << k << ": no message";
    EXPECT_TRUE(
        std::memcmp(r.normals.data(), input.data(), input.size() * sizeof(float)) == 0)
        << "allocation " << k << " failed (" << dacpo_status_string(r.status)
        << ") but the caller's normals were changed";
  }
  RecordProperty("failed_runs", std::to_string(failed));
  EXPECT_GT(failed, total / 2) << "most allocations are needed";
  dacpo_scene_free(&sc);
}
