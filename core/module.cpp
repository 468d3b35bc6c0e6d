#include "core/module.hpp"

#include <dlfcn.h>

#include <filesystem>
#include <map>
#include <mutex>
#include <system_error>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace rfd {
namespace {

std::vector<std::filesystem::path> module_folders() {
    std::vector<std::filesystem::path> folders;
    std::error_code ec;
    const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (!ec) folders.push_back(program.parent_path());
#ifdef RFD_MODULE_DIR
    folders.emplace_back(RFD_MODULE_DIR);
#endif
    return folders;
}

void* open_module(const std::string& name) {
    const std::string file = "librfd_" + name + ".so";
    std::string reasons;
    for (const std::filesystem::path& folder : module_folders()) {
        const std::filesystem::path path = folder / file;
        std::error_code ec;
        if (!std::filesystem::exists(path, ec)) continue;
        if (void* handle = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL)) return handle;
        reasons += std::string("; ") + dlerror();
    }
    throw ToolError(SourceLocation{file}, "cannot load this part of rfd (it belongs beside the rfd program)" + reasons);
}

}  // namespace

void* module_entry(const std::string& name, const std::string& symbol) {
    static std::mutex mutex;
    static std::map<std::pair<std::string, std::string>, void*> entries;
    const std::lock_guard lock(mutex);
    void*& entry = entries[{name, symbol}];
    if (entry != nullptr) return entry;
    static std::map<std::string, void*> handles;
    void*& handle = handles[name];
    if (handle == nullptr) handle = open_module(name);
    entry = dlsym(handle, symbol.c_str());
    if (entry == nullptr)
        throw ToolError(SourceLocation{"librfd_" + name + ".so"}, "has no entry point " + symbol);
    return entry;
}

}  // namespace rfd
