// Shared by the NeuS field kernels: the tetrahedron of the finite-difference normals. Its vertices
// sum to zero and sum v v^T = 4 I, so for f linear, sum_k v_k f(x + h v_k) / (4h) = grad f exactly
// and the mean of the four values is f(x) up to O(h^2).
#ifndef NF_NEUS_FIELD_GLSL
#define NF_NEUS_FIELD_GLSL

vec3 nf_tetra_vertex(uint k) {
  return k == 0u ? vec3(1.0, -1.0, -1.0) : k == 1u ? vec3(-1.0, -1.0, 1.0) : k == 2u ? vec3(-1.0, 1.0, -1.0)
                                                                                  : vec3(1.0, 1.0, 1.0);
}

#endif
