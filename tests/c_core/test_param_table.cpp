// SPDX-License-Identifier: BSD-3-Clause
// The parameter table (dacpo_param_table.h) is the one place a parameter's
// default is written: every field of dacpo_params is a row of it (viewpoint
// aside), and dacpo_params_init() gives the table's defaults.
#include <dacpo/dacpo.h>
#include <dacpo/dacpo_param_table.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <cstddef>
#include <cstring>
#include <vector>

namespace {

struct Field {
  size_t offset, size, align;
  const char* name;
};

std::vector<Field>
tableFields()
{
  std::vector<Field> f;
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, flag, doc)                                                     \
  f.push_back({offsetof(dacpo_params, name), sizeof(dacpo_params::name),                      \
               alignof(decltype(dacpo_params::name)), #name});
  DACPO_PARAMS()
#undef DACPO_PARAM
  f.push_back({offsetof(dacpo_params, viewpoint), sizeof(dacpo_params::viewpoint),
               alignof(double), "viewpoint"});
  return f;
}

} // namespace

// Sorted by offset, each field starts where the one before ends (plus the
// padding its alignment needs), and the last ends the struct: a field added to
// dacpo_params without a row leaves a hole and fails here.
TEST(DacpoParamTable, EveryFieldIsARow)
{
  std::vector<Field> f = tableFields();
  std::sort(f.begin(), f.end(), [](const Field& a, const Field& b) { return a.offset < b.offset; });
  size_t end = 0;
  for (const Field& x : f) {
    const size_t expect = (end + x.align - 1) / x.align * x.align;
    EXPECT_EQ(x.offset, expect) << "a field before " << x.name << " has no row in the table";
    end = x.offset + x.size;
  }
  EXPECT_LE(sizeof(dacpo_params) - end, alignof(dacpo_params)) << "a field after the last row";
}

// dacpo_params_init() gives each row's default, written in the table only.
TEST(DacpoParamTable, InitGivesTheTableDefaults)
{
  dacpo_params p;
  dacpo_params_init(&p);
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, flag, doc)                                                     \
  EXPECT_EQ(p.name, static_cast<decltype(p.name)>(def)) << #name;
  DACPO_PARAMS()
#undef DACPO_PARAM
  EXPECT_EQ(p.viewpoint[0], 0.0);
  char msg[256] = "";
  EXPECT_EQ(dacpo_params_validate(&p, msg, sizeof(msg)), DACPO_OK) << msg;
}

// dacpo_params_set takes every row by its name: numbers for numeric kinds, the
// value's name for enums.
TEST(DacpoParamsSet, EveryRowIsSettableByName)
{
  dacpo_params p;
  dacpo_params_init(&p);
  char msg[256] = "";
  size_t rows = 0;
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, flag, doc)                                     \
  ++rows;                                                                                     \
  EXPECT_EQ(dacpo_params_set(&p, #name, std::strcmp(#kind, "ENUM") ? "1" : "XX", msg,        \
                             sizeof(msg)),                                                    \
            std::strcmp(#kind, "ENUM") ? DACPO_OK : DACPO_ERR_INVALID_ARGUMENT)               \
      << #name << ": " << msg;
  DACPO_PARAMS()
#undef DACPO_PARAM
  EXPECT_GE(rows, 30u);
}

TEST(DacpoParamsSet, KnownValues)
{
  dacpo_params p;
  dacpo_params_init(&p);
  char msg[256] = "";
  ASSERT_EQ(dacpo_params_set(&p, "dipole_c", "2.5", msg, sizeof(msg)), DACPO_OK) << msg;
  EXPECT_EQ(p.dipole_c, 2.5);
  ASSERT_EQ(dacpo_params_set(&p, "dipole_c", "-1", msg, sizeof(msg)), DACPO_OK) << msg;
  EXPECT_EQ(p.dipole_c, -1.0);
  ASSERT_EQ(dacpo_params_set(&p, "k", "16", msg, sizeof(msg)), DACPO_OK) << msg;
  EXPECT_EQ(p.k, 16u);
  ASSERT_EQ(dacpo_params_set(&p, "seed", "18446744073709551615", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.seed, UINT64_MAX);
  ASSERT_EQ(dacpo_params_set(&p, "edge_weight", "overlap", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.edge_weight, DACPO_WEIGHT_OVERLAP);
  ASSERT_EQ(dacpo_params_set(&p, "disconnected", "bridge", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.disconnected, DACPO_DISCONNECTED_BRIDGE);
  ASSERT_EQ(dacpo_params_set(&p, "sign_policy", "keep", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.sign_policy, DACPO_SIGN_KEEP);
  ASSERT_EQ(dacpo_params_set(&p, "scan_kind", "single", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.scan_kind, DACPO_SCAN_SINGLE_VIEW);
  ASSERT_EQ(dacpo_params_set(&p, "ipsr_enabled", "0", msg, sizeof(msg)), DACPO_OK);
  EXPECT_EQ(p.ipsr_enabled, 0);
}

// A value the field cannot hold, or an unknown name, is refused with a message
// naming it, and nothing changes.
TEST(DacpoParamsSet, BadValuesLeaveTheParamsAsTheyWere)
{
  dacpo_params p, before;
  dacpo_params_init(&p);
  before = p;
  char msg[256] = "";
  const char* bad[][2] = {{"k", "-1"},           {"k", "ten"},          {"k", ""},
                          {"k", " 5"},           {"k", "5x"},           {"dipole_c", "nan"},
                          {"dipole_c", "inf"},   {"dipole_c", "1,5"},   {"ipsr_enabled", "2"},
                          {"num_threads", "4294967296"}, {"dipole_final_sweep", "2147483648"},
                          {"seed", "18446744073709551616"}, {"edge_weight", "VCR"},
                          {"scan_kind", "1"}};
  for (const auto& b : bad) {
    EXPECT_EQ(dacpo_params_set(&p, b[0], b[1], msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT)
        << b[0] << "=" << b[1];
    EXPECT_NE(std::strstr(msg, b[0]), nullptr) << msg;
    EXPECT_EQ(std::memcmp(&p, &before, sizeof(p)), 0) << b[0] << "=" << b[1];
  }
  EXPECT_EQ(dacpo_params_set(&p, "dipole_cc", "1", msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_NE(std::strstr(msg, "dipole_cc"), nullptr) << msg;
  EXPECT_EQ(dacpo_params_set(&p, "viewpoint", "1", msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_params_set(nullptr, "k", "1", msg, sizeof(msg)), DACPO_ERR_INVALID_ARGUMENT);
  EXPECT_EQ(dacpo_params_set(&p, "k", nullptr, nullptr, 0), DACPO_ERR_INVALID_ARGUMENT);
}

namespace {

// A field set to v: validate's verdict, and whether its message names the field.
template <typename T>
bool
acceptsValue(T dacpo_params::*field, double v, const char* name, bool* named)
{
  dacpo_params p;
  dacpo_params_init(&p);
  if constexpr (std::is_enum<T>::value)
    p.*field = static_cast<T>(static_cast<int>(v));
  else
    p.*field = static_cast<T>(v);
  char msg[256] = "";
  const bool ok = dacpo_params_validate(&p, msg, sizeof(msg)) == DACPO_OK;
  *named = std::strstr(msg, name) != nullptr;
  return ok;
}

// Both ends of a row's range are accepted; one step beyond either (where the
// field's type can hold it) is refused with a message that names the field.
template <typename T>
void
checkRange(T dacpo_params::*field, const char* name, double lo, double hi)
{
  const bool real = std::is_floating_point<T>::value;
  const double step = real ? 1e-6 * std::max(1.0, std::fabs(lo)) : 1.0;
  bool named = false;
  if (lo > -DACPO_INF) {
    EXPECT_TRUE(acceptsValue(field, lo, name, &named)) << name << " = " << lo;
    if (real || lo >= 1.0 || std::is_signed<T>::value || std::is_enum<T>::value) {
      EXPECT_FALSE(acceptsValue(field, lo - step, name, &named)) << name << " below " << lo;
      EXPECT_TRUE(named) << name;
    }
  }
  if (hi < DACPO_INF) {
    const double hstep = real ? 1e-6 * std::max(1.0, std::fabs(hi)) : 1.0;
    EXPECT_TRUE(acceptsValue(field, hi, name, &named)) << name << " = " << hi;
    EXPECT_FALSE(acceptsValue(field, hi + hstep, name, &named)) << name << " above " << hi;
    EXPECT_TRUE(named) << name;
  }
}

} // namespace

// The table's min and max columns are what dacpo_params_validate() enforces.
TEST(DacpoParamTable, EveryRowsRangeIsEnforced)
{
  size_t rows = 0;
#define DACPO_PARAM(kind, type, name, def, lo, hi, who, cli, flag, doc)       \
  ++rows;                                                                      \
  checkRange(&dacpo_params::name, #name, static_cast<double>(lo), static_cast<double>(hi));
  DACPO_PARAMS()
#undef DACPO_PARAM
  EXPECT_GE(rows, 30u);
}
