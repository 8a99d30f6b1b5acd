// Internal helpers of the parameter schema (render/param_schema.cpp) shared with the tools that
// print it (tools/param_table.cpp: docs/parameters.md), so a bound reads the same in a refusal
// message and in the documentation table.
#pragma once

#include <string>

namespace canopy {

// A number as a reader writes it: integers in full (16384, 1048576), others in 6 digits.
std::string formatParamNumber(double v);

}  // namespace canopy
