// TextDocument (text_document.h): one report, rendered as Markdown or HTML.
#include "platemeter/core/text_document.h"

#include <utility>

#include "platemeter/core/markup.h"

namespace platemeter {

void TextDocument::Heading(int level, std::string text) {
  TextBlock& b = blocks.emplace_back();
  b.kind = TextBlock::Kind::kHeading;
  b.level = level;
  b.text = std::move(text);
}

void TextDocument::Paragraph(std::string text) {
  TextBlock& b = blocks.emplace_back();
  b.kind = TextBlock::Kind::kParagraph;
  b.text = std::move(text);
}

TextTable& TextDocument::Table(std::vector<std::string> header, std::string align) {
  TextBlock& b = blocks.emplace_back();
  b.kind = TextBlock::Kind::kTable;
  b.table.header = std::move(header);
  b.table.align = std::move(align);
  return b.table;
}

void TextDocument::List(std::vector<std::string> items) {
  TextBlock& b = blocks.emplace_back();
  b.kind = TextBlock::Kind::kList;
  b.items = std::move(items);
}

namespace {

std::string MarkdownRow(const std::vector<std::string>& cells) {
  std::string out = "|";
  for (const std::string& c : cells) out += " " + c + " |";
  return out + "\n";
}

// Escaped text with **bold** as <strong>.
std::string HtmlInline(const std::string& text) {
  const std::string escaped = EscapeMarkup(text);
  std::string out;
  bool open = false;
  for (size_t i = 0; i < escaped.size(); ++i) {
    if (escaped.compare(i, 2, "**") == 0) {
      out += open ? "</strong>" : "<strong>";
      open = !open;
      ++i;
    } else {
      out += escaped[i];
    }
  }
  if (open) out += "</strong>";
  return out;
}

std::string HtmlTable(const TextTable& table) {
  auto cell = [&](const char* tag, size_t column, const std::string& text) {
    const bool right = column < table.align.size() && table.align[column] == 'r';
    return std::string("<") + tag + (right ? " class=\"num\">" : ">") + HtmlInline(text) + "</" + tag + ">";
  };
  std::string out = "<table>\n<thead><tr>";
  for (size_t c = 0; c < table.header.size(); ++c) out += cell("th", c, table.header[c]);
  out += "</tr></thead>\n<tbody>\n";
  for (const auto& row : table.rows) {
    out += "<tr>";
    for (size_t c = 0; c < row.size(); ++c) out += cell("td", c, row[c]);
    out += "</tr>\n";
  }
  return out + "</tbody>\n</table>\n";
}

}  // namespace

std::string ToMarkdown(const TextDocument& document) {
  std::string out;
  for (const TextBlock& b : document.blocks) {
    switch (b.kind) {
      case TextBlock::Kind::kHeading:
        out += (out.empty() ? "" : "\n") + std::string(b.level, '#') + " " + b.text + "\n";
        break;
      case TextBlock::Kind::kParagraph:
        out += "\n" + b.text + "\n";
        break;
      case TextBlock::Kind::kTable: {
        out += "\n" + MarkdownRow(b.table.header) + "|";
        for (size_t c = 0; c < b.table.header.size(); ++c) {
          out += c < b.table.align.size() && b.table.align[c] == 'r' ? "---:|" : "---|";
        }
        out += "\n";
        for (const auto& row : b.table.rows) out += MarkdownRow(row);
        break;
      }
      case TextBlock::Kind::kList:
        out += "\n";
        for (const std::string& item : b.items) out += "- " + item + "\n";
        break;
    }
  }
  return out;
}

std::string ToHtmlElements(const TextDocument& document) {
  std::string out;
  for (const TextBlock& b : document.blocks) {
    switch (b.kind) {
      case TextBlock::Kind::kHeading: {
        const std::string tag = "h" + std::to_string(b.level < 1 ? 1 : b.level > 6 ? 6 : b.level);
        out += "<" + tag + ">" + HtmlInline(b.text) + "</" + tag + ">\n";
        break;
      }
      case TextBlock::Kind::kParagraph:
        out += "<p>" + HtmlInline(b.text) + "</p>\n";
        break;
      case TextBlock::Kind::kTable:
        out += HtmlTable(b.table);
        break;
      case TextBlock::Kind::kList:
        out += "<ul>\n";
        for (const std::string& item : b.items) out += "<li>" + HtmlInline(item) + "</li>\n";
        out += "</ul>\n";
        break;
    }
  }
  return out;
}

}  // namespace platemeter
