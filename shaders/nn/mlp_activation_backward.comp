#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_EXT_control_flow_attributes : require
// dL/dz = dL/dy * act'(z) for one layer, elementwise over [batch][out_stride], in grad_z's layout
// (nf_rows.glsl; the others may be laid out otherwise); padding columns and padding samples get
// zero. A second copy, transposed ([out][zt_stride], samples contiguous), feeds the weight
// gradient (mlp_backward_weights.comp). An invocation takes four samples of one vec4 of columns,
// so that it writes whole vec4 to both (on lavapipe each store loops over the lanes; neighbouring
// lanes take neighbouring groups of four samples). grad_y and grad_z may be the same range only when laid out
// alike (each value is then read before its invocation writes it). Reads are texel fetches
// (straight-line gathers on lavapipe, where storage-buffer loads loop over the lanes) and the
// activation is a specialisation constant (lavapipe evaluates both sides of a branch).

layout(constant_id = 0) const uint WG = 256;
layout(constant_id = 1) const uint ACTIVATION = 0;  // NF_ACT_*
layout(local_size_x_id = 0) in;
#include "nf_index.glsl"
#include "nf_activation.glsl"
#include "nf_rows.glsl"

layout(std430, binding = 0) writeonly buffer GradZ { vec4 grad_z[]; };
layout(std430, binding = 1) writeonly buffer GradZT { vec4 grad_zt[]; };
layout(binding = 16) uniform samplerBuffer grad_y;
layout(binding = 17) uniform samplerBuffer y;  // the layer's output (ReLU, Softplus)
layout(binding = 18) uniform samplerBuffer z;  // its pre-activation (Sine)

layout(push_constant) uniform Push {
  uint quads;   // groups of four samples to write: batch rounded up to 8 when interleaved, / 4
  uint batch;
  uint out_dim;
  uint out4;    // out_stride / 4
  float beta;
  float omega;
  uint grad_z_interleaved;  // nf_rows.glsl layouts
  uint grad_y_interleaved;
  uint y_interleaved;       // of y and z
  uint zt_stride4;          // vec4 per row of grad_zt
} pc;

void main() {
  const uint i = nf_linear_index();
  if (i >= pc.quads * pc.out4) return;
  const uint f4 = i / pc.quads, first = 4u * (i % pc.quads), column = f4 * 4u;
  const bool z_interleaved = pc.grad_z_interleaved != 0u;
  mat4 out_grad;  // out_grad[t]: sample first + t
  [[unroll]] for (uint t = 0u; t < 4u; ++t) {
    const uint s = first + t;
    vec4 g = vec4(0.0), d = vec4(1.0);
    if (s < pc.batch) {  // padding samples read nothing: done in place, their clamped reads would race
      const int y_at = int(nf_row_index(s, f4, pc.out4, pc.y_interleaved != 0u));
      g = texelFetch(grad_y, int(nf_row_index(s, f4, pc.out4, pc.grad_y_interleaved != 0u)));
      if (ACTIVATION == NF_ACT_SINE) {
        const vec4 zv = texelFetch(z, y_at);
        [[unroll]] for (uint e = 0u; e < 4u; ++e) d[e] = nf_activate_derivative(ACTIVATION, pc.beta, pc.omega, 0.0, zv[e]);
      } else if (ACTIVATION != NF_ACT_NONE) {
        const vec4 yv = texelFetch(y, y_at);
        [[unroll]] for (uint e = 0u; e < 4u; ++e) d[e] = nf_activate_derivative(ACTIVATION, pc.beta, pc.omega, yv[e], 0.0);
      }
    }
    [[unroll]] for (uint e = 0u; e < 4u; ++e) out_grad[t][e] = column + e < pc.out_dim && s < pc.batch ? g[e] * d[e] : 0.0;
    grad_z[nf_row_index(s, f4, pc.out4, z_interleaved)] = out_grad[t];
  }
  const mat4 columns = transpose(out_grad);  // columns[e]: column + e of the four samples
  [[unroll]] for (uint e = 0u; e < 4u; ++e)
    if (column + e < pc.out_dim) grad_zt[(column + e) * pc.zt_stride4 + first / 4u] = columns[e];
}
