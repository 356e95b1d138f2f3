#pragma once
#include <string>

namespace eds {

// "MAJOR.MINOR.PATCH (commit <git describe>)", fixed when the library was built.
std::string versionString();

}  // namespace eds
