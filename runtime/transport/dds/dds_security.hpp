// DDS Security's participant properties for Fast DDS's builtin plugins (internal to pbppo::dds).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "runtime/transport/dds/dds_endpoint.hpp"

namespace pbppo::dds {

// dds.sec.auth / access / crypto properties pointing at the security folder's files.
std::vector<std::pair<std::string, std::string>> SecurityProperties(const DdsSecurity& security);

}  // namespace pbppo::dds
