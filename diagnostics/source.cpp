#include "diagnostics/source.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "diagnostics/cli_catalogue.hpp"

namespace sidc {

SourceFile::SourceFile(std::string file_name, std::string contents)
    : name(std::move(file_name)), text(std::move(contents)) {
  line_starts.push_back(0);
  for (std::size_t i = 0; i < text.size(); ++i)
    if (text[i] == '\n') line_starts.push_back(i + 1);
}

SourceFile::Position SourceFile::position(std::size_t offset) const {
  offset = std::min(offset, text.size());
  auto it = std::upper_bound(line_starts.begin(), line_starts.end(), offset);
  const auto line = static_cast<int>(it - line_starts.begin());
  return {line, static_cast<int>(offset - line_starts[static_cast<std::size_t>(line - 1)]) + 1};
}

std::string_view SourceFile::line_text(int line) const {
  if (line < 1 || static_cast<std::size_t>(line) > line_starts.size()) return {};
  const std::size_t begin = line_starts[static_cast<std::size_t>(line - 1)];
  std::size_t end = text.find('\n', begin);
  if (end == std::string::npos) end = text.size();
  if (end > begin && text[end - 1] == '\r') --end;
  return std::string_view(text).substr(begin, end - begin);
}

std::variant<std::string, Diagnostic> read_text_file(const std::string& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) return cli_diag::is_directory(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) return cli_diag::cannot_read(path, std::strerror(errno));
  std::ostringstream contents;
  contents << in.rdbuf();
  return std::move(contents).str();
}

std::optional<std::string> read_whole_file(const std::string& path, std::string& error) {
  auto text = read_text_file(path);
  if (auto* d = std::get_if<Diagnostic>(&text)) {
    error = render(*d);
    return std::nullopt;
  }
  return std::get<std::string>(std::move(text));
}

}  // namespace sidc
