#pragma once
// The record of what `rfd make` made, so a second run skips what has not changed.
//
// Each step's key is a hash of what it depends on: the rfd that runs it, its command line,
// and the content of every file it reads. The manifest (DIR/manifest.json) keeps, per step,
// that key and the content hash of every file it wrote. A step is skipped when its key is
// the recorded one and its outputs still hash as recorded; otherwise it runs again (and so
// does every step whose inputs its new outputs change, because their keys change).
//
// Hashes are XXH3 128-bit (libxxhash): they detect change, they do not guard against an
// adversary, and they read a 150 MB pattern in a fraction of a second.

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace rfd::project {

/// Hex digest of a file's content, or of a folder's: every regular file below it, by
/// relative name in sorted order, names and contents both hashed. IoError when unreadable.
std::string content_hash(const std::filesystem::path& path);

/// Hex digest of several strings, each length-prefixed so that no two lists collide by
/// concatenation.
std::string hash_strings(const std::vector<std::string>& parts);

struct StepRecord {
    std::string key;
    std::map<std::string, std::string> outputs;  ///< path relative to the output folder -> content hash
};

class Manifest {
public:
    /// Reads `folder`/manifest.json; a missing file is an empty manifest, a damaged one is
    /// an empty manifest too (everything reruns) after a note on stderr.
    static Manifest read(const std::filesystem::path& folder);
    /// Writes `folder`/manifest.json atomically.
    void write() const;

    /// True when `step` was made with `key` and each recorded output still has its hash.
    bool up_to_date(const std::string& step, const std::string& key) const;
    void record(const std::string& step, StepRecord record) { steps_[step] = std::move(record); }
    void forget(const std::string& step) { steps_.erase(step); }
    const std::map<std::string, StepRecord>& steps() const { return steps_; }

private:
    std::filesystem::path folder_;
    std::map<std::string, StepRecord> steps_;
};

}  // namespace rfd::project
