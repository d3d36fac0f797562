/* SPDX-License-Identifier: BSD-3-Clause */
/* Shared by the pcl_dacpo_* tools: the command line. An option table
 * (OptionSpec) gives -h, the parser and the unknown-option check with typo
 * hints; strict number parsing. The templates are here, the rest in
 * dacpo_tool_options.cpp (library dacpo_tool_io); tools only (not installed). */
#pragma once

#include <pcl/console/print.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace dacpo_tool {

/** Lower-case extension including the dot (".pcd"), or "". */
std::string
extension(const std::string& path);

/** Positional .pcd/.ply arguments in command-line order; values of the options
 *  named in \a value_options (e.g. "-colored out.pcd") are not positional. */
std::vector<std::string>
fileArguments(int argc,
              char** argv,
              const std::vector<const char*>& value_options = {});

/** Edit distance (insert, delete, substitute) of two short strings. */
std::size_t
editDistance(const std::string& a, const std::string& b);

/** Every argument must be a known switch, a known option followed by its
 *  value, or a .pcd/.ply file: a typo ("-frobnicate 3", "--k 5") must not run
 *  silently with defaults. On failure returns false with a message naming the
 *  argument and, when one is close, the option meant. */
bool
checkArguments(int argc,
               char** argv,
               const std::vector<const char*>& switches,
               const std::vector<const char*>& valued,
               std::string& error);

/** The class of a pointer to member (Options for std::string Options::*). */
template <typename Member>
struct MemberOf;
template <typename Class, typename T>
struct MemberOf<T Class::*> {
  using type = Class;
};

/** Setter of an OptionSpec for an option whose value is kept as given (the tool
 *  checks it afterwards): setText<&Options::field>. */
template <auto Field>
bool
setText(typename MemberOf<decltype(Field)>::type& o, const std::string& s, std::string&)
{
  o.*Field = s;
  return true;
}

/** Setter of an OptionSpec for a switch: setFlag<&Options::field>. */
template <auto Field>
bool
setFlag(typename MemberOf<decltype(Field)>::type& o, const std::string&, std::string&)
{
  o.*Field = true;
  return true;
}

/** One command-line option of a tool's table. The help text (printOptionTable),
 *  the parser (applyOptions) and the unknown-option check (checkOptionTable) all
 *  read the tool's table, so an option is named once. */
template <typename Options, typename Defaults>
struct OptionSpec {
  const char* name;
  const char* arg;  /* nullptr: a switch; else the value's placeholder in -h */
  const char* help; /* '\n' starts a continuation line */
  /* the default shown in -h; nullptr: none */
  std::string (*shown)(const Defaults&);
  /* sets the options from the value (a switch gets ""); false + error */
  bool (*apply)(Options&, const std::string&, std::string&);
  /* a method switch kept for measurement: listed apart in -h */
  bool expert = false;
};

/** The table entry named \a name, or nullptr. */
template <typename Spec, std::size_t N>
const Spec*
findOption(const Spec (&table)[N], const char* name)
{
  for (const Spec& spec : table)
    if (std::strcmp(spec.name, name) == 0)
      return &spec;
  return nullptr;
}

/** The switches (\a with_value false) or the options that take a value, for
 *  checkArguments and fileArguments. */
template <typename Spec, std::size_t N>
std::vector<const char*>
optionNames(const Spec (&table)[N], bool with_value)
{
  std::vector<const char*> names;
  for (const Spec& spec : table)
    if ((spec.arg != nullptr) == with_value)
      names.push_back(spec.name);
  return names;
}

/** checkArguments with the switches and valued options of \a table. */
template <typename Spec, std::size_t N>
bool
checkOptionTable(const Spec (&table)[N], int argc, char** argv, std::string& error)
{
  return checkArguments(
      argc, argv, optionNames(table, false), optionNames(table, true), error);
}

/** Applies the options in command-line order: a repeated option keeps its last
 *  value; a missing value or a setter's refusal is printed, then false. */
template <typename Spec, std::size_t N, typename Options>
bool
applyOptions(const Spec (&table)[N], int argc, char** argv, Options& o)
{
  for (int i = 1; i < argc; ++i) {
    const Spec* spec = findOption(table, argv[i]);
    if (spec == nullptr)
      continue; /* a file (unknown options were rejected before) */
    std::string value, error;
    if (spec->arg != nullptr) {
      if (i + 1 >= argc || argv[i + 1][0] == '\0') {
        const bool file = std::strncmp(spec->arg, "F.", 2) == 0;
        pcl::console::print_error("Error: %s needs a %s (%s)\n",
                                  spec->name,
                                  file ? "file name" : "value",
                                  spec->arg);
        return false;
      }
      value = argv[++i];
    }
    if (!spec->apply(o, value, error)) {
      pcl::console::print_error("Error: %s %s\n", spec->name, error.c_str());
      return false;
    }
  }
  return true;
}

/** Help lines wrap at this many characters (the parameter table's one-line
 *  docs; hand-written helps break their own lines with '\n'). */
constexpr std::size_t kHelpWidth = 56;

/** \a text with every line longer than \a width broken at its last space
 *  before that width. */
std::string
wrapHelp(const std::string& text, std::size_t width);

/** One entry of -h (see printOptionTable). */
template <typename Spec, typename Defaults>
void
printOption(const Spec& spec, const Defaults& defaults, std::size_t head_width, std::size_t indent)
{
  std::string head = spec.name;
  if (spec.arg)
    head += std::string(" ") + spec.arg;
  if (head.size() < head_width)
    head.resize(head_width, ' ');
  std::string text = wrapHelp(spec.help, kHelpWidth);
  for (std::size_t at = text.find('\n'); at != std::string::npos; at = text.find('\n', at + 1))
    text.insert(at + 1, indent, ' ');
  pcl::console::print_info("                     %s = %s", head.c_str(), text.c_str());
  if (spec.shown) {
    pcl::console::print_info(" (default: ");
    pcl::console::print_value("%s", spec.shown(defaults).c_str());
    pcl::console::print_info(")");
  }
  pcl::console::print_info("\n");
}

/** The options part of -h, one entry per option: 21 spaces, the name and the
 *  value's placeholder padded to \a head_width, " = ", the help with its
 *  continuation lines indented by \a indent, and the default if shown; the
 *  expert options after the others, under their own heading. */
template <typename Spec, std::size_t N, typename Defaults>
void
printOptionTable(const Spec (&table)[N],
                 const Defaults& defaults,
                 std::size_t head_width,
                 std::size_t indent)
{
  for (int expert = 0; expert < 2; ++expert) {
    if (expert)
      pcl::console::print_info("  method switches (for measurement and ablation):\n");
    for (const Spec& spec : table)
      if (spec.expert == (expert != 0))
        printOption(spec, defaults, head_width, indent);
  }
}


/** Strict parse of a non-negative integer (no sign, no trailing junk). */
bool
toUnsigned(const std::string& s, std::uint64_t& v);

/** Strict parse of a finite number. */
bool
toDouble(const std::string& s, double& v);

} // namespace dacpo_tool
