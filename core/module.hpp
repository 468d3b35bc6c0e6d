#pragma once
// Modules: the parts of rfd that wrap a heavy third-party library, loaded on first use.
//
// OpenImageIO brings about 260 shared libraries with it and OpenCV about 30; loading them
// costs a program close to half a second and 130 MB before main() runs. rfd keeps each
// behind a small interface in a module (librfd_<name>.so, built beside the programs), so
// that a command which never reads an image, and a test which never calls OpenCV, starts
// in milliseconds. A module holds only adaptor code: it uses no symbol of rfd's libraries,
// so it can never see a second copy of their state.
//
// Example: auto* backend = load_module<ImageBackend>("imageio", "rfd_imageio_backend");

#include <string>

namespace rfd {

/// The entry point `symbol` of module `name`, a function taking nothing and returning a
/// pointer to the module's interface. The module is looked up beside the running program,
/// then in the build's program folder; it is loaded once and stays loaded. Throws
/// ToolError naming the module file when it cannot be loaded or lacks the symbol.
void* module_entry(const std::string& name, const std::string& symbol);

/// The interface a module's entry point returns, loaded once per (name, symbol).
template <class Interface>
Interface& load_module(const std::string& name, const std::string& symbol) {
    using Entry = Interface* (*)();
    return *reinterpret_cast<Entry>(module_entry(name, symbol))();
}

}  // namespace rfd
