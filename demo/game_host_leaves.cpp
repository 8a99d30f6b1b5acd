// canopy-game-host's falling leaves: a host compute shader moves them by canopyWindAt through
// Canopy's wind image (host_leaves.comp), another draws them (host_leaves.vert/frag); the self-check
// compares their velocity with sampleCanopyWind (demo/game_host.cpp).
#include "game_host.h"

#include "host_leaves.comp.h"
#include "host_leaves.frag.h"
#include "host_leaves.vert.h"

namespace game {

// The leaves: their buffer (host-visible, filled here), the descriptor set (Canopy's wind image and
// the buffer), the compute pipeline that moves them and the one that draws them (depth tested
// against the host's depth after Canopy's passes, not written).
bool createLeaves(Game& g, const glm::vec4& area) {
  g.leafArea = area;
  VkBufferCreateInfo bci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  bci.size = VkDeviceSize(kLeaves) * 32;
  bci.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
  HOST_CHECK(vkCreateBuffer(g.dev.device, &bci, nullptr, &g.leaves));
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(g.dev.device, g.leaves, &req);
  VkMemoryAllocateInfo mai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  mai.allocationSize = req.size;
  const int32_t type = host::memoryType(g.dev.memory, req.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                                        VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  if (type < 0) return false;
  mai.memoryTypeIndex = uint32_t(type);
  HOST_CHECK(vkAllocateMemory(g.dev.device, &mai, nullptr, &g.leavesMemory));
  HOST_CHECK(vkBindBufferMemory(g.dev.device, g.leaves, g.leavesMemory, 0));
  float* mapped = nullptr;
  HOST_CHECK(vkMapMemory(g.dev.device, g.leavesMemory, 0, VK_WHOLE_SIZE, 0, reinterpret_cast<void**>(&mapped)));
  uint32_t state = 12345u;
  auto next = [&] { return float((state = state * 1664525u + 1013904223u) >> 8) / float(1u << 24); };
  for (uint32_t i = 0; i < kLeaves; ++i) {
    const float x = area.x + (2.0f * next() - 1.0f) * area.z, y = area.w * next(), z = area.y + (2.0f * next() - 1.0f) * area.z;
    const float leaf[8] = {x, y, z, next(), 0.0f, 0.0f, 0.0f, 0.0f};
    std::memcpy(mapped + 8 * i, leaf, sizeof leaf);
  }
  vkUnmapMemory(g.dev.device, g.leavesMemory);
  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};  // texelFetch: the sampler's settings do not matter
  HOST_CHECK(vkCreateSampler(g.dev.device, &si, nullptr, &g.windSampler));
  const VkDescriptorSetLayoutBinding b[2] = {
      {0, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
      {1, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT | VK_SHADER_STAGE_VERTEX_BIT, nullptr}};
  VkDescriptorSetLayoutCreateInfo li{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  li.bindingCount = 2;
  li.pBindings = b;
  HOST_CHECK(vkCreateDescriptorSetLayout(g.dev.device, &li, nullptr, &g.leafSetLayout));
  const VkDescriptorPoolSize ps[2] = {{VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 1}, {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1}};
  VkDescriptorPoolCreateInfo pi{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
  pi.maxSets = 1;
  pi.poolSizeCount = 2;
  pi.pPoolSizes = ps;
  HOST_CHECK(vkCreateDescriptorPool(g.dev.device, &pi, nullptr, &g.leafPool));
  VkDescriptorSetAllocateInfo ai{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
  ai.descriptorPool = g.leafPool;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &g.leafSetLayout;
  HOST_CHECK(vkAllocateDescriptorSets(g.dev.device, &ai, &g.leafSet));
  // Canopy's wind image lives as long as the context: one descriptor, written once.
  canopy::CanopyWind wind;
  const canopy::Status ws = canopy::canopyWind(g.ctx, &wind);
  if (!ws.ok()) return std::fprintf(stderr, "canopy-game-host: %s\n", ws.message().c_str()), false;
  const VkDescriptorImageInfo ii{g.windSampler, wind.view, wind.state.layout};
  const VkDescriptorBufferInfo bi{g.leaves, 0, VK_WHOLE_SIZE};
  VkWriteDescriptorSet w[2] = {{VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET}, {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET}};
  w[0].dstSet = w[1].dstSet = g.leafSet;
  w[0].descriptorCount = w[1].descriptorCount = 1;
  w[0].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  w[0].pImageInfo = &ii;
  w[1].dstBinding = 1;
  w[1].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  w[1].pBufferInfo = &bi;
  vkUpdateDescriptorSets(g.dev.device, 2, w, 0, nullptr);
  VkPushConstantRange computeRange{VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(canopy::CanopyWindInfo) + 2 * sizeof(glm::vec4)};
  VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pl.setLayoutCount = 1;
  pl.pSetLayouts = &g.leafSetLayout;
  pl.pushConstantRangeCount = 1;
  pl.pPushConstantRanges = &computeRange;
  HOST_CHECK(vkCreatePipelineLayout(g.dev.device, &pl, nullptr, &g.leafComputeLayout));
  VkPushConstantRange drawRange{VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof(glm::mat4) + 2 * sizeof(glm::vec4)};
  pl.pPushConstantRanges = &drawRange;
  HOST_CHECK(vkCreatePipelineLayout(g.dev.device, &pl, nullptr, &g.leafDrawLayout));
  VkShaderModuleCreateInfo mi{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  mi.codeSize = sizeof(host_leaves_comp);
  mi.pCode = host_leaves_comp;
  VkShaderModule module = VK_NULL_HANDLE;
  HOST_CHECK(vkCreateShaderModule(g.dev.device, &mi, nullptr, &module));
  VkComputePipelineCreateInfo cpi{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  cpi.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO, nullptr, 0, VK_SHADER_STAGE_COMPUTE_BIT, module, "main", nullptr};
  cpi.layout = g.leafComputeLayout;
  const VkResult r = vkCreateComputePipelines(g.dev.device, VK_NULL_HANDLE, 1, &cpi, nullptr, &g.leafCompute);
  vkDestroyShaderModule(g.dev.device, module, nullptr);
  HOST_CHECK(r);
  VkPipelineDepthStencilStateCreateInfo ds = host::depthTested(VK_COMPARE_OP_LESS);
  ds.depthWriteEnable = VK_FALSE;
  HOST_CHECK(host::createHostPipeline(g.dev.device, g.leafDrawLayout,
                                      {host_leaves_vert, sizeof(host_leaves_vert), host_leaves_frag, sizeof(host_leaves_frag)},
                                      kColorFormat, g.depthFormat, g.depthFormat, ds, false, &g.leafDraw));
  return true;
}

// The falling leaves: moved by this frame's wind (Canopy's image, in the state recordCanopy left it
// for the host's shaders: no barrier of the host's), then drawn over the scene and copied to the
// slot's readback.
bool recordLeaves(Game& g, const Scene& sc, Slot& s, VkCommandBuffer cmd, uint64_t number, const glm::mat4& view, const glm::mat4& vp) {
  host::bufferBarrier(cmd, g.leaves, VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | kCopy,
                      VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT | VK_ACCESS_2_TRANSFER_READ_BIT,
                      VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT);
  canopy::CanopyWind wind;
  const canopy::Status ws = canopy::canopyWind(g.ctx, &wind);
  if (!ws.ok()) {
    std::fprintf(stderr, "canopy-game-host: %s\n", ws.message().c_str());
    return false;
  }
  struct {
    canopy::CanopyWindInfo wind;
    glm::vec4 area, step;
  } push{wind.info, g.leafArea, glm::vec4(1.0f / 30.0f, float(number) / 30.0f, float(kLeaves), 0.0f)};
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, g.leafCompute);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, g.leafComputeLayout, 0, 1, &g.leafSet, 0, nullptr);
  vkCmdPushConstants(cmd, g.leafComputeLayout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof push, &push);
  vkCmdDispatch(cmd, (kLeaves + 63) / 64, 1, 1);
  host::bufferBarrier(cmd, g.leaves, VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT,
                      VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | kCopy, VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_TRANSFER_READ_BIT);
  host::beginBoxPass(cmd, g.color.view, g.depth.view, true, false, {}, 1.0f, kW, kH, g.leafDraw);
  vkCmdBindDescriptorSets(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, g.leafDrawLayout, 0, 1, &g.leafSet, 0, nullptr);
  const glm::mat4 inv = glm::inverse(view);
  const float size = 0.015f * (sc.plantMax.y - sc.plantMin.y);  // half a leaf
  struct {
    glm::mat4 viewProj;
    glm::vec4 right, up;
  } draw{vp, glm::vec4(glm::vec3(inv[0]) * size, 40.0f * size), glm::vec4(glm::vec3(inv[1]) * size, 0.0f)};
  vkCmdPushConstants(cmd, g.leafDrawLayout, VK_SHADER_STAGE_VERTEX_BIT, 0, sizeof draw, &draw);
  vkCmdDraw(cmd, g.drawLeaves ? 6 * kLeaves : 0, 1, 0, 0);
  vkCmdEndRendering(cmd);
  const VkBufferCopy copy{0, 14 * VkDeviceSize(kW) * kH, VkDeviceSize(kLeaves) * 32};
  vkCmdCopyBuffer(cmd, g.leaves, s.readback.buffer, 1, &copy);
  return true;
}

}  // namespace game
