#include "tools/example_passes.h"

#include <algorithm>

#include "engine/device.h"
#include "engine/pass_slots.h"
#include "tools/test_shaders.h"

namespace canopy {

Status createExamplePipelines(Device& d, ExamplePipelines* out) {
  *out = ExamplePipelines{};
  // The example passes' shaders are the tests' (tools/test_shaders.h), not the runtime's.
  auto desc = [](const char* shader, uint32_t push) {
    ComputePipelineDesc x{shader, push};
    x.shaderLookup = &canopy_test::findEmbeddedShader;
    return x;
  };
  CANOPY_TRY(createComputePipeline(d, desc("example_write.comp", sizeof(gpu::ExampleWriteParams)), &out->write));
  CANOPY_TRY(createComputePipeline(d, desc("example_transform.comp", sizeof(gpu::ExampleTransformParams)), &out->transform));
  CANOPY_TRY(createComputePipeline(d, desc("example_reduce.comp", sizeof(gpu::ExampleReduceParams)), &out->reduce));
  return Status();
}

void destroyExamplePipelines(Device& d, ExamplePipelines& p) {
  destroyComputePipeline(d, p.write);
  destroyComputePipeline(d, p.transform);
  destroyComputePipeline(d, p.reduce);
}

Status buildExampleGraph(Device& d, const ExamplePipelines& pipes, const ExampleParams& prm, const Buffer& result,
                         ExampleGraph* out) {
  if (prm.width == 0 || prm.height == 0 || prm.passCount < 1 || prm.passCount > 3)
    return Status::error("example graph: width/height must be > 0 and passCount in [1, 3]");
  rg::RenderGraph& g = out->graph;
  const uint32_t n = prm.width * prm.height;
  out->values = g.createBuffer("values", {VkDeviceSize(n) * sizeof(float)});
  ImageDesc img;
  img.format = VK_FORMAT_R32_SFLOAT;
  img.width = prm.width;
  img.height = prm.height;
  img.usage = VK_IMAGE_USAGE_TRANSFER_SRC_BIT;  // inspectable after the frame (tests read it back)
  out->image = g.createImage("transformed", img);
  out->result = g.importBuffer("result", sizeof(gpu::ExampleResult), {}, rg::stateOf(rg::Use::HostRead));
  const ExamplePipelines* p = &pipes;

  // Each pass's descriptors and graph uses from one slot list (engine/pass_slots.h).
  using rg::Use;
  rg::addSlotPass(g, "write", {rg::slot(out->values, Use::ComputeStorageWrite)}, [=](rg::PassContext& c, const rg::Slots& s) {
    const gpu::ExampleWriteParams pc{n, prm.seed, prm.scale};
    return rg::dispatchSlots(c, p->write, s, n, 1, 1, pc);
  });
  if (prm.passCount >= 2)
    rg::addSlotPass(g, "transform", {rg::slot(out->values, Use::ComputeStorageRead), rg::slot(out->image, Use::ComputeStorageWrite)},
                    [=](rg::PassContext& c, const rg::Slots& s) {
                      const gpu::ExampleTransformParams pc{prm.width, prm.height, prm.gain, prm.bias};
                      return rg::dispatchSlots(c, p->transform, s, prm.width, prm.height, 1, pc);
                    });
  if (prm.passCount >= 3)
    rg::addSlotPass(g, "reduce", {rg::slot(out->image, Use::ComputeStorageRead), rg::slot(out->result, Use::ComputeStorageWrite)},
                    [=](rg::PassContext& c, const rg::Slots& s) {
                      const gpu::ExampleReduceParams pc{prm.width, prm.height};
                      return rg::dispatchSlots(c, p->reduce, s, 256, 1, 1, pc);
                    });
  // Prefix graphs (timing a pass alone) keep their last pass alive explicitly.
  if (prm.passCount == 1) g.markOutput(out->values);
  if (prm.passCount == 2) g.markOutput(out->image);
  CANOPY_TRY(g.compile());
  CANOPY_TRY(g.realize(d));
  return g.bindBuffer(out->result, result.buffer);
}

ExampleReference exampleReference(const ExampleParams& prm) {
  ExampleReference r;
  const uint32_t n = prm.width * prm.height;
  r.image.resize(n);
  r.minValue = 1e300;
  r.maxValue = -1e300;
  for (uint32_t i = 0; i < n; ++i) {
    float v = float(gpu::canopyHash(i + prm.seed) & 0xffffu) * (prm.scale / 65536.0f);
    double t = double(prm.gain) * v + prm.bias;
    r.image[i] = float(t);
    r.sum += t;
    r.minValue = std::min(r.minValue, t);
    r.maxValue = std::max(r.maxValue, t);
  }
  return r;
}

}  // namespace canopy
