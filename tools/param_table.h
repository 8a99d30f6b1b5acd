#pragma once
// docs/parameters.md from the parameter schema (<canopy/canopy_schema.h>): one table per parameter
// struct, one row per field. `canopy-demo --param-table` prints it; a unit test compares the file.
#include <string>

namespace canopy {

std::string paramTableMarkdown();

}  // namespace canopy
