#include "project/manifest.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <memory>
#include <system_error>

#include <nlohmann/json.hpp>
#include <xxhash.h>

#include "core/error.hpp"
#include "core/files.hpp"
#include "core/progress.hpp"

namespace rfd::project {
namespace {

namespace fs = std::filesystem;

struct StateDeleter {
    void operator()(XXH3_state_t* state) const { XXH3_freeState(state); }
};
using HashState = std::unique_ptr<XXH3_state_t, StateDeleter>;

HashState new_state() {
    HashState state(XXH3_createState());
    if (!state || XXH3_128bits_reset(state.get()) != XXH_OK) throw std::bad_alloc();
    return state;
}

void update(XXH3_state_t* state, const std::string& text) {
    const std::uint64_t size = text.size();
    XXH3_128bits_update(state, &size, sizeof size);
    XXH3_128bits_update(state, text.data(), text.size());
}

void update_with_file(XXH3_state_t* state, const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    if (!in) throw IoError(SourceLocation{file.string()}, "cannot read to hash it");
    std::vector<char> buffer(1 << 20);
    while (in) {
        in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
        XXH3_128bits_update(state, buffer.data(), static_cast<std::size_t>(in.gcount()));
    }
    if (in.bad()) throw IoError(SourceLocation{file.string()}, "read failed while hashing it");
}

std::string hex(XXH3_state_t* state) {
    const XXH128_hash_t digest = XXH3_128bits_digest(state);
    char text[33];
    std::snprintf(text, sizeof text, "%016llx%016llx", static_cast<unsigned long long>(digest.high64),
                  static_cast<unsigned long long>(digest.low64));
    return text;
}

}  // namespace

std::string content_hash(const fs::path& path) {
    HashState state = new_state();
    std::error_code ec;
    if (fs::is_directory(path, ec)) {
        std::vector<fs::path> files;
        for (fs::recursive_directory_iterator it(path, ec), end; !ec && it != end; it.increment(ec))
            if (it->is_regular_file(ec)) files.push_back(fs::relative(it->path(), path));
        if (ec) throw IoError(SourceLocation{path.string()}, "cannot list the folder to hash it: " + ec.message());
        std::sort(files.begin(), files.end());
        for (const fs::path& file : files) {
            update(state.get(), file.generic_string());
            update_with_file(state.get(), path / file);
        }
    } else if (fs::exists(path, ec) && !fs::is_regular_file(path, ec)) {
        throw IoError(SourceLocation{path.string()}, "not a regular file (a device or a pipe?): rfd reads files and folders");
    } else {
        update_with_file(state.get(), path);
    }
    return hex(state.get());
}

std::string hash_strings(const std::vector<std::string>& parts) {
    HashState state = new_state();
    for (const std::string& part : parts) update(state.get(), part);
    return hex(state.get());
}

Manifest Manifest::read(const fs::path& folder) {
    Manifest manifest;
    manifest.folder_ = folder;
    const fs::path file = folder / "manifest.json";
    std::error_code ec;
    if (!fs::exists(file, ec)) return manifest;
    try {
        std::ifstream in(file);
        const nlohmann::json json = nlohmann::json::parse(in);
        for (const auto& [name, step] : json.at("steps").items()) {
            StepRecord record;
            record.key = step.at("key").get<std::string>();
            for (const auto& [path, hash] : step.at("outputs").items()) record.outputs[path] = hash.get<std::string>();
            manifest.steps_[name] = std::move(record);
        }
    } catch (const nlohmann::json::exception& error) {
        Progress::note(file.string() + " is damaged (" + error.what() + "): every step runs again");
        manifest.steps_.clear();
    }
    return manifest;
}

void Manifest::write() const {
    nlohmann::json steps = nlohmann::json::object();
    for (const auto& [name, record] : steps_)
        steps[name] = {{"key", record.key}, {"outputs", record.outputs}};
    const nlohmann::json json = {
        {"about", "what rfd make made here: per step, the hash of its inputs and of each output it wrote"},
        {"steps", steps}};
    write_text_file(folder_ / "manifest.json", json.dump(2) + "\n");
}

bool Manifest::up_to_date(const std::string& step, const std::string& key) const {
    const auto found = steps_.find(step);
    if (found == steps_.end() || found->second.key != key) return false;
    for (const auto& [path, hash] : found->second.outputs) {
        std::error_code ec;
        if (!fs::exists(folder_ / path, ec) || content_hash(folder_ / path) != hash) return false;
    }
    return true;
}

}  // namespace rfd::project
