#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// dL/dz = dL/dy * act'(z) for an MLP's top layer, elementwise over [batch][out_stride]: the
// caller's output gradient and the layer's kept tensor are sample-major, dz goes out lane-
// interleaved (nf_rows.glsl) for the input adjoint, and transposed ([out][zt_stride], samples
// contiguous) for the weight gradient (mlp_weights_bwd.comp); padding columns and padding
// samples get zero. Hidden layers get theirs from the input adjoint above (mlp_fwd.comp,
// ADJOINT). An invocation takes four samples of one vec4 of columns, so that it writes whole vec4
// to both (on lavapipe each store loops over the lanes; neighbouring lanes take neighbouring
// groups of four samples). Reads are texel fetches (straight-line gathers on lavapipe, where
// storage-buffer loads loop over the lanes) and the activation is a specialisation constant
// (lavapipe evaluates both sides of a branch).

layout(constant_id = 0) const uint WG = 256;
layout(constant_id = 1) const uint ACTIVATION = 0;  // NF_ACT_*
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_activation.glsl"
#include "nf_rows.glsl"

layout(std430, binding = 0) writeonly buffer GradZ { vec4 grad_z[]; };
layout(std430, binding = 1) writeonly buffer GradZT { vec4 grad_zt[]; };
layout(binding = 16) uniform samplerBuffer grad_y;  // [batch][out4]
layout(binding = 17) uniform samplerBuffer kept;    // [batch][out4]: the layer's output (z for Sine)

layout(push_constant) uniform Push {
  uint quads;   // groups of four samples to write: batch rounded up to 8, / 4
  uint batch;
  uint out_dim;
  uint out4;    // out_stride / 4
  float beta;
  float omega;
  uint zt_stride4;  // vec4 per row of grad_zt
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.quads * pc.out4) return;
  const uint f4 = i / pc.quads, first = 4u * (i % pc.quads), column = f4 * 4u;
  mat4 out_grad;  // out_grad[t]: sample first + t
  [[unroll]] for (uint t = 0u; t < 4u; ++t) {
    const uint s = first + t;
    vec4 g = vec4(0.0), d = vec4(1.0);
    if (s < pc.batch) {  // padding samples read nothing
      const int at = int(s * pc.out4 + f4);
      g = texelFetch(grad_y, at);
      if (ACTIVATION != NF_ACT_NONE) {
        const vec4 v = texelFetch(kept, at);
        [[unroll]] for (uint e = 0u; e < 4u; ++e) d[e] = nf_activate_derivative_kept(ACTIVATION, pc.beta, pc.omega, v[e]);
      }
    }
    [[unroll]] for (uint e = 0u; e < 4u; ++e) out_grad[t][e] = column + e < pc.out_dim && s < pc.batch ? g[e] * d[e] : 0.0;
    grad_z[nf_row_index(s, f4, pc.out4, true)] = out_grad[t];
  }
  const mat4 columns = transpose(out_grad);  // columns[e]: column + e of the four samples
  [[unroll]] for (uint e = 0u; e < 4u; ++e)
    if (column + e < pc.out_dim) grad_zt[(column + e) * pc.zt_stride4 + first / 4u] = columns[e];
}
