// Internal to the env layer: a Vec3 into the `double[3]` of the C interfaces a world speaks
// (plugin_abi.h, external_world.h).
#pragma once

#include "hapticd/servo/environment_port.hpp"

namespace hapticd::env::detail {

inline void to_array(const servo::Vec3& v, double (&out)[3]) noexcept {
    out[0] = v.x;
    out[1] = v.y;
    out[2] = v.z;
}

}  // namespace hapticd::env::detail
