#pragma once
// Writing outputs so that a failure leaves nothing half-written: write to a temporary file beside
// the target, then rename it into place (rename is atomic within one file system).

#include <filesystem>
#include <functional>

namespace vox {

/// Calls `write(tmp_path)` to produce the file, then renames it to `target`. If `write` throws,
/// the temporary file is removed and the exception propagates; `target` is untouched.
/// Creates the target's parent folder when missing.
void write_atomically(const std::filesystem::path& target,
                      const std::function<void(const std::filesystem::path&)>& write);

} // namespace vox
