// Built against an installed Canopy: creates a context on a synthetic crown and destroys it.
#include <cstdio>

#include <render/canopy.h>
#include <render/leaf_cloud.h>

int main() {
  canopy::DeviceDesc dd;
  dd.applicationName = "canopy-consumer";
  canopy::Device dev;
  canopy::Status s = canopy::createDevice(dd, &dev);
  if (!s.ok()) {
    std::fprintf(stderr, "consumer: %s\n", s.message().c_str());
    return 1;
  }
  canopy::CanopyDesc desc;
  desc.width = 64;
  desc.height = 48;
  desc.useRootCache = false;
  canopy::CanopyContext* ctx = nullptr;
  s = canopy::createCanopy(dev, canopy::makeLeafCloud(200, 1), desc, &ctx);
  if (s.ok()) std::printf("consumer: Canopy context created (%u leaves)\n", canopy::canopyStats(ctx).layers.leafCount);
  else std::fprintf(stderr, "consumer: %s\n", s.message().c_str());
  canopy::destroyCanopy(ctx);
  canopy::destroyDevice(dev);
  return s.ok() ? 0 : 1;
}
