// TextDocument: one report rendered as Markdown and as HTML, the same cells.
#include <gtest/gtest.h>

#include "platemeter/core/text_document.h"

namespace platemeter {
namespace {

TextDocument Sample() {
  TextDocument doc;
  doc.Heading(1, "Title");
  doc.Paragraph("Summary with <angle> & **bold**.");
  doc.Heading(2, "Constants");
  TextTable& t = doc.Table({"Parameter", "Value"}, "lr");
  t.rows.push_back({"c_mm", "80.0033"});
  t.rows.push_back({"k1 < 0", "±1e-06"});
  doc.List({"**not determined**: xp_mm", "plain"});
  return doc;
}

TEST(TextDocument, MarkdownHasTheTablesAlignmentAndNoLeadingBlankLine) {
  const std::string md = ToMarkdown(Sample());
  EXPECT_EQ(md,
            "# Title\n\nSummary with <angle> & **bold**.\n\n## Constants\n\n| Parameter | Value |\n|---|---:|\n"
            "| c_mm | 80.0033 |\n| k1 < 0 | ±1e-06 |\n\n- **not determined**: xp_mm\n- plain\n");
}

TEST(TextDocument, HtmlEscapesTextMarksNumbersAndBold) {
  const std::string html = ToHtmlElements(Sample());
  EXPECT_NE(html.find("<h1>Title</h1>"), std::string::npos);
  EXPECT_NE(html.find("<p>Summary with &lt;angle&gt; &amp; <strong>bold</strong>.</p>"), std::string::npos);
  EXPECT_NE(html.find("<td>c_mm</td><td class=\"num\">80.0033</td>"), std::string::npos) << html;
  EXPECT_NE(html.find("<td>k1 &lt; 0</td>"), std::string::npos);
  EXPECT_NE(html.find("<li><strong>not determined</strong>: xp_mm</li>"), std::string::npos);
  EXPECT_EQ(html.find("**"), std::string::npos);
}

}  // namespace
}  // namespace platemeter
