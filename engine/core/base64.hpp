#pragma once
// Base64 (RFC 4648, with padding): how images travel inside JSON requests as data URLs.
#include <string>
#include <string_view>

namespace nf {

std::string base64_encode(std::string_view bytes);

}  // namespace nf
