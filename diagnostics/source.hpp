// A model file's text and the spans that point into it.
//
// Every diagnostic and every compiled operation carries a Span, so that a message can show the
// offending line with a caret and the runtime can name the term that failed on the data.
// Lines and columns are 1-based (stanc3's Location.ml, but 1-based as editors count).
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace sidc {

struct SourceFile {
  std::string name;  // as given on the command line; shown in diagnostics
  std::string text;
  std::vector<std::size_t> line_starts;  // byte offset of each line's first character

  SourceFile(std::string file_name, std::string contents);

  struct Position {
    int line = 1;
    int column = 1;
  };
  Position position(std::size_t offset) const;
  std::string_view line_text(int line) const;  // without the line break
};

// A half-open byte range [begin, end) of one source file; `file` may be null for spans made by a
// pass (such as the integration constants), which then print without a location.
struct Span {
  std::shared_ptr<const SourceFile> file;
  std::size_t begin = 0;
  std::size_t end = 0;

  bool known() const { return file != nullptr; }
  SourceFile::Position start() const { return file ? file->position(begin) : SourceFile::Position{0, 0}; }
  std::size_t length() const { return end > begin ? end - begin : 0; }
};

}  // namespace sidc
