#include "diagnostics/source.hpp"

#include <algorithm>

#include "diagnostics/cli_catalogue.hpp"
#include "diagnostics/regular_file.hpp"

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
  // Only a regular file, read whole (regular_file.hpp): a FIFO or /dev/zero is refused at once.
  auto read = read_regular_file(path);
  if (auto* refusal = std::get_if<FileRefusal>(&read)) {
    switch (refusal->kind) {
      case FileRefusal::Kind::directory: return cli_diag::is_directory(path);
      case FileRefusal::Kind::not_regular: return cli_diag::not_a_regular_file(path, refusal->reason);
      case FileRefusal::Kind::cannot_open:
      case FileRefusal::Kind::changed:
      case FileRefusal::Kind::no_memory: return cli_diag::cannot_read(path, refusal->reason);
    }
  }
  const auto& bytes = std::get<FileBytes>(read);
  return std::string(bytes.data.get(), bytes.size);
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
