#include "tools/param_table.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include <canopy/canopy.h>

#include "render/param_schema.h"

namespace canopy {
namespace {

// What a reader needs of the check: the allowed values.
std::string allowed(const ParamInfo& p) {
  const std::string lo = formatParamNumber(p.min), hi = formatParamNumber(p.max);
  switch (p.check) {
    case ParamCheck::Closed: return "[" + lo + ", " + hi + "]";
    case ParamCheck::AboveMin: return "(" + lo + ", " + hi + "]";
    case ParamCheck::Enum: return p.unit;
    case ParamCheck::PowerOfTwo: return "power of two in [" + lo + ", " + hi + "]";
    case ParamCheck::PowerOfTwoOrZero: return "0, or a power of two in [" + lo + ", " + hi + "]";
    case ParamCheck::Finite: return "finite";
    case ParamCheck::Nested: return "its own table";
    case ParamCheck::Each: return "at most " + hi + ", each by its table";
    default: return "—";
  }
}

// The default as the list writes it, without the parentheses that keep its commas out of the macro.
std::string defaultText(const char* text) {
  std::string s = text;
  if (s.size() >= 2 && s.front() == '(' && s.back() == ')') s = s.substr(1, s.size() - 2);
  return s;
}

// A table cell: a '|' would end the cell in Markdown (GitHub's tables, also inside a code span), so
// each is escaped with a backslash, which renders as the bar.
std::string cell(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '|') out += '\\';
    out += c;
  }
  return out;
}

}  // namespace

std::string paramTableMarkdown() {
  std::string out =
      "# Parameters\n\n"
      "Generated from the parameter schema (`<canopy/canopy_schema.h>`: each struct of `<canopy/canopy_params.h>` is\n"
      "declared by one list line per field) by `canopy-demo --param-table > docs/parameters.md`; the unit\n"
      "test `ParamSchema.DocsTableMatchesTheSchema` fails when this file and the schema differ. The same\n"
      "lines give each struct its `operator==`, `checkParams()` (run by `createCanopy` and\n"
      "`setCanopyParams` when values are given, not every frame) and the demo's `--help` text for the\n"
      "options that mirror a field. Fields checked together (a layout against `CanopyDesc.maxLayers`, the\n"
      "region split's order, the simulation plane's axes, a warp cell against `minCellSize`) are\n"
      "described with their structs in the header.\n";
  size_t n = 0;
  const ParamInfo* t = paramSchema(&n);
  const char* owner = "";
  for (size_t i = 0; i < n; ++i) {
    const ParamInfo& p = t[i];
    if (std::string(owner) != p.owner) {
      owner = p.owner;
      out += std::string("\n## ") + owner + "\n\n| field | type | default | allowed | unit | what |\n|---|---|---|---|---|---|\n";
    }
    const std::string unit = p.check == ParamCheck::Enum ? std::string() : p.unit;
    out += "| `" + cell(p.name) + "` | `" + cell(p.type) + "` | `" + cell(defaultText(p.defaultText)) + "` | " +
           cell(allowed(p)) + " | " + cell(unit) + " | " + cell(p.doc) + " |\n";
  }
  return out;
}

}  // namespace canopy
