#pragma once
// The message of the rfd::Error an action throws, or "" when it throws none.

#include <functional>
#include <string>

#include "core/error.hpp"

namespace rfd::testing {

inline std::string error_of(const std::function<void()>& action) {
    try {
        action();
    } catch (const Error& error) {
        return error.what();
    }
    return "";
}

}  // namespace rfd::testing
