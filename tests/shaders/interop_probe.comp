#version 460
#extension GL_GOOGLE_include_directive : require
#include "shared/interop_probe.h"

// Writes every field of the push-constant InteropProbe to fixed float slots, in declaration
// order; the C++ test compares slot by slot with the values it pushed.
layout(local_size_x = 1) in;
layout(push_constant, scalar) uniform Push { InteropProbe probe; };
layout(binding = 0, std430) writeonly buffer Out { float slots[]; };

void main() {
  slots[0] = probe.a;
  slots[1] = probe.b.x; slots[2] = probe.b.y; slots[3] = probe.b.z;
  slots[4] = float(probe.c);
  slots[5] = probe.d.x; slots[6] = probe.d.y;
  for (int i = 0; i < 4; ++i) slots[7 + i] = float(probe.e[i]);
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r) slots[11 + c * 4 + r] = probe.m[c][r];
}
