#include "core/error.hpp"

#include <cstdio>
#include <cstdlib>

namespace rfd {

std::string SourceLocation::to_string() const {
    std::string text = file;
    if (line > 0) {
        text += ":" + std::to_string(line);
        if (column > 0) text += ":" + std::to_string(column);
    }
    if (!key.empty()) text += (text.empty() ? "" : ": ") + key;
    return text;
}

Error::Error(const SourceLocation& where, const std::string& message)
    : std::runtime_error(where.to_string().empty() ? message
                                                   : where.to_string() + ": " + message) {}

void rethrow_at(const Error& cause, const SourceLocation& where, const std::string& message) {
    if (dynamic_cast<const IoError*>(&cause)) throw IoError(where, message);
    if (dynamic_cast<const ToolError*>(&cause)) throw ToolError(where, message);
    throw InputError(where, message);
}

void check_failed(const char* condition, const char* file, int line,
                  const std::string& message) {
    std::fprintf(stderr, "rfd: internal error: %s:%d: check failed: %s%s%s\n", file, line,
                 condition, message.empty() ? "" : ": ", message.c_str());
    std::abort();
}

}  // namespace rfd
