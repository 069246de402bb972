#pragma once
// A report as blocks (headings, paragraphs, tables, lists) whose text is
// formatted once and rendered as Markdown (report.md) or as the body of an HTML
// page (report.html): both print the same numbers, formatted in one place.
// Inline markup: **bold** only (rendered as <strong> in HTML).
#include <string>
#include <vector>

namespace platemeter {

struct TextTable {
  std::vector<std::string> header;
  std::string align;  // one character per column: 'l' left, 'r' right (numbers)
  std::vector<std::vector<std::string>> rows;
};

struct TextBlock {
  enum class Kind { kHeading, kParagraph, kTable, kList };
  Kind kind = Kind::kParagraph;
  int level = 1;     // kHeading: 1 = the title, 2 = a section, 3 = a subsection
  std::string text;  // kHeading, kParagraph
  TextTable table;   // kTable
  std::vector<std::string> items;  // kList
};

struct TextDocument {
  std::vector<TextBlock> blocks;

  void Heading(int level, std::string text);
  void Paragraph(std::string text);
  // Returns the new table for its rows to be added.
  TextTable& Table(std::vector<std::string> header, std::string align);
  void List(std::vector<std::string> items);
};

std::string ToMarkdown(const TextDocument& document);
// The blocks as HTML elements (h1..h3, p, table, ul), text escaped; no <html>
// or <body>: the caller places them in its page.
std::string ToHtmlElements(const TextDocument& document);

}  // namespace platemeter
