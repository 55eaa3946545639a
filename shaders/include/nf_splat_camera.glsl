// The push-constant block shared by the projection kernels of strand rasterisation (108 bytes:
// within the 128 bytes lavapipe allows). Host twin: ProjectPush in engine/splat/rasterizer.cpp.
#ifndef NF_SPLAT_CAMERA_GLSL
#define NF_SPLAT_CAMERA_GLSL
layout(push_constant) uniform Push {
  vec4 r0, r1, r2;  // rows of the world-to-camera [R | t] (OpenGL camera axes)
  float fx, fy, cx, cy;
  uint width, height;
  float near_plane, far_plane;
  float k2, eps2, delta2;  // segment Gaussian: length_scale^2, width^2, guard^2
  float low_pass, orientation_guard;
  uint strands, points_per_strand;
} pc;
#endif
