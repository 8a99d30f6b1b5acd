#pragma once
// Small helpers the layer files share (render/layers.h's parts): CPU time, MiB text, the frame
// block's and the next set's graph states.
#include <chrono>
#include <cstdio>
#include <string>

#include "engine/render_graph.h"

namespace canopy {

inline double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

inline uint64_t roundUp(uint64_t x, uint64_t a) { return (x + a - 1) / a * a; }

inline std::string mib(uint64_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / double(1 << 20));
  return buf;
}

// The frame block is read by the vertex stage (boundaries, matrices) and the fragment stage (light).
inline const rg::State kFrameRead{VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                                  VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_IMAGE_LAYOUT_UNDEFINED};

// The next set rests where the cross-fade reads it.
inline const rg::State kNextRest = rg::stateOf(rg::Use::FragmentSampled);

}  // namespace canopy
