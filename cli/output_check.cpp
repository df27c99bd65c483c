#include "cli/output_check.hpp"

#include <filesystem>
#include <unistd.h>

#include "diagnostics/cli_catalogue.hpp"

namespace sidc {
namespace fs = std::filesystem;

std::optional<std::string> output_problem(const std::string& option, const std::string& path, OutputKind kind) {
  if (path.empty()) return std::nullopt;
  auto problem = [&](const std::string& reason) { return render(cli_diag::output_not_writable(option, path, reason)); };
  std::error_code ec;
  const fs::path target(path);  // as given, so that messages name what the user wrote
  const auto status = fs::status(target, ec);
  if (fs::exists(status)) {
    if (kind == OutputKind::file && fs::is_directory(status)) return problem("it is a directory; name a file");
    if (kind == OutputKind::directory && !fs::is_directory(status)) return problem("it is a file, not a directory");
    if (kind == OutputKind::directory) {
      if (::access(target.c_str(), W_OK | X_OK) != 0) return problem("the directory is not writable");
      return std::nullopt;
    }
  }
  // The writers create missing folders on the way, and a file goes in beside a temporary one: the
  // nearest folder that exists must be a folder, and writable.
  fs::path folder = target.parent_path();
  while (!folder.empty() && !fs::exists(folder, ec) && folder != folder.parent_path()) folder = folder.parent_path();
  if (folder.empty()) folder = ".";
  if (!fs::is_directory(folder, ec)) return problem("`" + folder.string() + "` is a file, not a directory");
  if (::access(folder.c_str(), W_OK | X_OK) != 0) return problem("`" + folder.string() + "` is not writable");
  return std::nullopt;
}

}  // namespace sidc
