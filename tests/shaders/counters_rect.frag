#version 460
// tests/counters_test.cpp: a flat colour for the counted rectangle.
layout(location = 0) out vec4 outColor;

void main() { outColor = vec4(0.2, 0.6, 0.3, 1.0); }
