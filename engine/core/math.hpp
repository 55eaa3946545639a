#pragma once
// Math aliases: GLM vectors and matrices under short project-wide names.
#include <glm/glm.hpp>

namespace nf {
using vec2 = glm::vec2;
using vec3 = glm::vec3;
using vec4 = glm::vec4;
using dvec3 = glm::dvec3;
using mat3 = glm::mat3;
using mat4 = glm::mat4;
using uvec2 = glm::uvec2;
using uvec3 = glm::uvec3;
}  // namespace nf
