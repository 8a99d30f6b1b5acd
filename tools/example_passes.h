#pragma once
// The foundation's example compute graph: write (a hashed pattern into a buffer) -> transform
// (gain/bias into an R32F storage image) -> reduce (sum/min/max in one workgroup). It exercises
// transient buffers and images, layout transitions and an imported host-readable result; the
// smoke program times it and tests/compute_graph_test.cpp checks it against exampleReference().
#include <vector>

#include "engine/memory.h"
#include "engine/pipeline.h"
#include "engine/render_graph.h"
#include "shaders/shared/example.h"

namespace canopy {

struct ExampleParams {
  uint32_t width = 256, height = 256;
  uint32_t seed = 7;
  float scale = 2.0f;
  float gain = 3.0f, bias = -1.0f;
  // 1..3: how many of write/transform/reduce to include (prefixes, used to time passes alone).
  int passCount = 3;
};

struct ExamplePipelines {
  ComputePipeline write, transform, reduce;
};
Status createExamplePipelines(Device& device, ExamplePipelines* out);
void destroyExamplePipelines(Device& device, ExamplePipelines& p);

struct ExampleGraph {
  rg::RenderGraph graph;
  rg::ResourceId values = rg::kInvalidResource, image = rg::kInvalidResource, result = rg::kInvalidResource;
};

// Declares, compiles and realizes the graph. `result` (sizeof(gpu::ExampleResult) bytes) is
// imported and left readable by the host after each frame.
Status buildExampleGraph(Device& device, const ExamplePipelines& pipelines, const ExampleParams& params,
                         const Buffer& result, ExampleGraph* out);

// CPU reference: the transformed image (row-major) and its reduction, in double precision.
struct ExampleReference {
  std::vector<float> image;
  double sum = 0, minValue = 0, maxValue = 0;
};
ExampleReference exampleReference(const ExampleParams& params);

}  // namespace canopy
