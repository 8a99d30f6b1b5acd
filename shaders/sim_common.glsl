// Bindings and helpers shared by the simulation kernels (compute/simulation.cpp declares the
// same eight bindings for each of them).
#include "shared/sim.h"

// Single-workgroup kernels exchange data between invocations through these buffers between
// barriers, so they declare them coherent; the one-pass kernels (advect, tile) must not pay for it.
#ifndef SIM_COHERENT
#define SIM_COHERENT coherent
#endif

layout(binding = 0, scalar) readonly buffer FrameBuf { SimFrame frameIn; };
// The frame, loaded once per invocation (LOAD_FRAME() first in main): the shared helpers take it by
// value, and passing the buffer member itself copies all 256 bytes from memory at every call
// (measured on lavapipe: 1.35 ms of the projection's 1.7 ms outside the V-cycles).
SimFrame f;
#define LOAD_FRAME() f = frameIn
// The motors' mass source at p (shared/sim.h, motorSource), summed in the CPU reference's order;
// reads the global frame rather than taking it as an argument (a copy per call on lavapipe).
float motorSourcesAt(vec2 p) {
  float q = 0.0;
  for (uint m = 0u; m < f.motorCount; ++m) q += motorSource(f.motors[m], p);
  return q;
}
// Velocity: field A at 0, field B at velocityFloats(n) (MAC faces or Stam's collocated arrays).
layout(binding = 1, scalar) SIM_COHERENT buffer VelBuf { float vel[]; };
layout(binding = 2, scalar) SIM_COHERENT buffer MgBuf { float mg[]; };
layout(binding = 3, scalar) SIM_COHERENT buffer WaveBuf { vec2 wave[]; };
layout(binding = 4, scalar) buffer TiledBuf { vec2 tiled[]; };
layout(binding = 5, scalar) writeonly buffer RingBuf { vec2 ring[]; };
layout(binding = 6, scalar) writeonly buffer RingTimesBuf { float ringTimes[]; };
layout(push_constant, scalar) uniform Push { SimPush pc; };

// Single-workgroup kernels: every invocation strides over the work, SYNC() separates phases.
#define SYNC() memoryBarrierBuffer(); barrier()
// Width of the single-workgroup kernels (constant_id 0 = their local_size_x_id): lavapipe runs a
// workgroup on one core, eight lanes at a time, so a narrow group there wastes nothing and pays
// for fewer lanes per barrier; a GPU wants the widest (docs/performance.md).
layout(constant_id = 0) const uint SIM_GROUP = SIM_MAX_GROUP_SIZE;
#define FOR_EACH(var, count) for (uint var = gl_LocalInvocationIndex; var < (count); var += SIM_GROUP)

bool isSource(uint side) { return (f.windSides & side) != 0u; }
// Inflow is prescribed on source sides only in the wind tunnel; in a closed box (walls) no net
// flow can enter, so there the wind pushes the first interior faces instead (as in Stam's scheme).
bool isInflow(uint side) { return f.boundary == SIM_BOUNDARY_TUNNEL && isSource(side); }
bool isOutflow(uint side) { return f.boundary == SIM_BOUNDARY_TUNNEL && !isSource(side); }

// MAC boundary faces of the field at `o`: inflow on source sides, 0 on walls, zero-gradient on
// outflow sides (reads the neighbouring interior face: call after a SYNC that published it).
void macBoundary(uint o) {
  uint n = f.n;
  FOR_EACH(k, 4u * n) {
    uint side = k / n, t = k % n;
    float s = (float(t) + 0.5) / float(n);
    if (side == 0u)
      vel[o + macU(n, 0u, t)] = isInflow(SIM_SIDE_LEFT) ? inflowSpeed(f, SIM_SIDE_LEFT, s)
                              : isOutflow(SIM_SIDE_LEFT) ? vel[o + macU(n, 1u, t)] : 0.0;
    else if (side == 1u)
      vel[o + macU(n, n, t)] = isInflow(SIM_SIDE_RIGHT) ? -inflowSpeed(f, SIM_SIDE_RIGHT, s)
                             : isOutflow(SIM_SIDE_RIGHT) ? vel[o + macU(n, n - 1u, t)] : 0.0;
    else if (side == 2u)
      vel[o + macV(n, t, 0u)] = isInflow(SIM_SIDE_BOTTOM) ? inflowSpeed(f, SIM_SIDE_BOTTOM, s)
                              : isOutflow(SIM_SIDE_BOTTOM) ? vel[o + macV(n, t, 1u)] : 0.0;
    else
      vel[o + macV(n, t, n)] = isInflow(SIM_SIDE_TOP) ? -inflowSpeed(f, SIM_SIDE_TOP, s)
                             : isOutflow(SIM_SIDE_TOP) ? vel[o + macV(n, t, n - 1u)] : 0.0;
  }
}

#ifndef SIM_NO_GROUP_SUM
shared float sGroupSum[SIM_GROUP];
// Sum over the workgroup (single-workgroup kernels; every invocation must call it).
float groupSum(float x) {
  sGroupSum[gl_LocalInvocationIndex] = x;
  barrier();
  for (uint w = SIM_GROUP / 2u; w > 0u; w >>= 1u) {
    if (gl_LocalInvocationIndex < w) sGroupSum[gl_LocalInvocationIndex] += sGroupSum[gl_LocalInvocationIndex + w];
    barrier();
  }
  float total = sGroupSum[0];
  barrier();
  return total;
}
#endif

// Walls mode: the wind of each source side as a body force on the first interior faces (dt * speed
// per step, like Stam's add_source), added to the field at `o`.
void wallWindForce(uint o) {
  if (f.boundary != SIM_BOUNDARY_WALLS) return;
  uint n = f.n;
  FOR_EACH(k, 4u * n) {
    uint side = k / n, t = k % n;
    float s = (float(t) + 0.5) / float(n);
    if (side == 0u && isSource(SIM_SIDE_LEFT)) vel[o + macU(n, 1u, t)] += f.dt * inflowSpeed(f, SIM_SIDE_LEFT, s);
    if (side == 1u && isSource(SIM_SIDE_RIGHT)) vel[o + macU(n, n - 1u, t)] -= f.dt * inflowSpeed(f, SIM_SIDE_RIGHT, s);
    if (side == 2u && isSource(SIM_SIDE_BOTTOM)) vel[o + macV(n, t, 1u)] += f.dt * inflowSpeed(f, SIM_SIDE_BOTTOM, s);
    if (side == 3u && isSource(SIM_SIDE_TOP)) vel[o + macV(n, t, n - 1u)] -= f.dt * inflowSpeed(f, SIM_SIDE_TOP, s);
  }
}
