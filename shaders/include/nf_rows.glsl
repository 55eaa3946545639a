// Where vec4 f4 of sample s lies in a batch tensor of stride4 vec4 per sample: sample-major rows
// (the layout between modules, engine/nn/mlp_config.hpp), or lane-interleaved groups of eight
// samples, [s / 8][f4][s % 8] (an MLP's hidden activations and gradients: eight neighbouring lanes
// then read 128 contiguous bytes instead of eight rows' worth of cache lines).
#ifndef NF_ROWS_GLSL
#define NF_ROWS_GLSL

const uint NF_ROW_GROUP = 8u;

uint nf_row_index(uint s, uint f4, uint stride4, bool interleaved) {
  return interleaved ? ((s >> 3) * stride4 + f4) * NF_ROW_GROUP + (s & 7u) : s * stride4 + f4;
}

#endif
