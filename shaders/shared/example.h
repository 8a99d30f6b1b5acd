// Push constants and results of the example write -> transform -> reduce graph (foundation
// smoke program and tests/compute_graph_test.cpp).
#ifndef CANOPY_EXAMPLE_H
#define CANOPY_EXAMPLE_H
#include "shared/interop.h"

CANOPY_NAMESPACE_BEGIN

struct ExampleWriteParams {
  uint count;   // number of values
  uint seed;    // input pattern seed
  float scale;  // values lie in [0, scale)
};
CANOPY_SIZE_CHECK(ExampleWriteParams, 12)

struct ExampleTransformParams {
  uint width;   // image width; values are read row-major, width * height of them
  uint height;
  float gain;   // image = gain * value + bias
  float bias;
};
CANOPY_SIZE_CHECK(ExampleTransformParams, 16)

struct ExampleReduceParams {
  uint width;
  uint height;
};
CANOPY_SIZE_CHECK(ExampleReduceParams, 8)

struct ExampleResult {
  float sum;
  float minValue;
  float maxValue;
  uint count;
};
CANOPY_SIZE_CHECK(ExampleResult, 16)

// Integer hash (lowbias32) used to generate the input; identical on both sides.
CANOPY_INLINE uint canopyHash(uint x) {
  x ^= x >> 16;
  x *= 0x7feb352du;
  x ^= x >> 15;
  x *= 0x846ca68bu;
  x ^= x >> 16;
  return x;
}

CANOPY_NAMESPACE_END
#endif
