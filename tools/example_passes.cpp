#include "tools/example_passes.h"

#include <algorithm>

#include "engine/device.h"

namespace canopy {

Status createExamplePipelines(Device& d, ExamplePipelines* out) {
  *out = ExamplePipelines{};
  CANOPY_TRY(createComputePipeline(d, {"example_write.comp", sizeof(gpu::ExampleWriteParams)}, &out->write));
  CANOPY_TRY(createComputePipeline(d, {"example_transform.comp", sizeof(gpu::ExampleTransformParams)},
                                   &out->transform));
  CANOPY_TRY(createComputePipeline(d, {"example_reduce.comp", sizeof(gpu::ExampleReduceParams)}, &out->reduce));
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
  const ExampleGraph* o = out;
  Device* dev = &d;

  g.addPass("write", [=](rg::PassContext& c) {
     gpu::ExampleWriteParams pc{n, prm.seed, prm.scale};
     return dispatch(*dev, c.cmd, p->write, n, 1, 1, {bindBuffer(c.buffer(o->values))}, pc);
   }).write(out->values, rg::Use::ComputeStorageWrite);
  if (prm.passCount >= 2)
    g.addPass("transform", [=](rg::PassContext& c) {
       gpu::ExampleTransformParams pc{prm.width, prm.height, prm.gain, prm.bias};
       return dispatch(*dev, c.cmd, p->transform, prm.width, prm.height, 1,
                       {bindBuffer(c.buffer(o->values)), bindImage(c.image(o->image).view)}, pc);
     })
        .read(out->values, rg::Use::ComputeStorageRead)
        .write(out->image, rg::Use::ComputeStorageWrite);
  if (prm.passCount >= 3)
    g.addPass("reduce", [=](rg::PassContext& c) {
       gpu::ExampleReduceParams pc{prm.width, prm.height};
       return dispatch(*dev, c.cmd, p->reduce, 256, 1, 1,
                       {bindImage(c.image(o->image).view), bindBuffer(c.buffer(o->result))}, pc);
     })
        .read(out->image, rg::Use::ComputeStorageRead)
        .write(out->result, rg::Use::ComputeStorageWrite);
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
