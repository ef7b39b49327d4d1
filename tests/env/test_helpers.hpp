// Shared helpers of the env tests: finite differences of a penalty force and matrix checks.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "hapticd/env/environment.hpp"

namespace hapticd::env::testing {

/// -∂f/∂x (column j = -∂f/∂x_j) by central differences of `evaluate(x, v).force_n`.
template <typename Object>
Mat3 fd_stiffness(const Object& object, const Vec3& x, const Vec3& v, double h = 1e-7) {
    Mat3 out(0.0);
    for (int j = 0; j < 3; ++j) {
        Vec3 dx(0.0);
        dx[j] = h;
        out[j] =
            -(object.evaluate(x + dx, v).force_n - object.evaluate(x - dx, v).force_n) / (2.0 * h);
    }
    return out;
}

/// -∂f/∂v by central differences.
template <typename Object>
Mat3 fd_damping(const Object& object, const Vec3& x, const Vec3& v, double h = 1e-7) {
    Mat3 out(0.0);
    for (int j = 0; j < 3; ++j) {
        Vec3 dv(0.0);
        dv[j] = h;
        out[j] =
            -(object.evaluate(x, v + dv).force_n - object.evaluate(x, v - dv).force_n) / (2.0 * h);
    }
    return out;
}

inline void expect_near(const Mat3& actual, const Mat3& expected, double tolerance,
                        const std::string& what) {
    for (int c = 0; c < 3; ++c) {
        for (int r = 0; r < 3; ++r) {
            EXPECT_NEAR(actual[c][r], expected[c][r], tolerance)
                << what << " at row " << r << ", column " << c;
        }
    }
}

inline void expect_near(const Vec3& actual, const Vec3& expected, double tolerance,
                        const std::string& what) {
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(actual[i], expected[i], tolerance) << what << " component " << i;
    }
}

}  // namespace hapticd::env::testing
