// Mutations of the fuzz harness (mutator.h).
#include "fuzz/mutator.h"

#include <algorithm>
#include <cctype>
#include <cstring>

namespace platemeter::fuzz {
namespace {

// Numbers that break parsers and arithmetic: overflow, denormals, integer
// limits, non-finite words, forms from_chars and toml++ treat differently.
const std::vector<std::string>& ExtremeNumbers() {
  static const std::vector<std::string> values = {
      "1e308", "-1e308", "1e-320", "5e-324", "1.7976931348623157e308", "1e999", "-1e999", "nan", "-nan", "inf",
      "-inf", "9223372036854775807", "-9223372036854775808", "9223372036854775808", "2147483647", "2147483648",
      "-2147483649", "4294967296", "-0", "0", "-1", "1e7", "10000001", "1e155", "1e-155", "0x10", "+1", "1.",
      ".5", "1e", "--1", "1_000", "0.0000000000000000000000000000001", "18446744073709551616", ""};
  return values;
}

// Fields and strings that break text handling.
std::string OddText(std::mt19937_64& random) {
  static const std::vector<std::string> values = {
      "\xEF\xBB\xBF", "\xff\xfe", "\xc3", "\xed\xa0\x80", "\xc0\xaf", "\xf4\x90\x80\x80", "\x01", "\x7f", "\t",
      "\"", "\"\"", ",", "#", "=", "[", "]]", "{", "}", "'", "\\", std::string("\0", 1), "X1Y1", "\xe2\x80\xae", "a\rb"};
  const size_t pick = random() % (values.size() + 2);
  if (pick == values.size()) return std::string(1 + random() % 20000, 'A');  // a huge field
  if (pick == values.size() + 1) return std::string(1, static_cast<char>(random() % 256));
  return values[pick];
}

// Lines of `text` as [begin, end) ranges including their '\n'.
std::vector<std::pair<size_t, size_t>> Lines(const std::string& text) {
  std::vector<std::pair<size_t, size_t>> lines;
  size_t begin = 0;
  while (begin < text.size()) {
    const size_t newline = text.find('\n', begin);
    const size_t end = newline == std::string::npos ? text.size() : newline + 1;
    lines.emplace_back(begin, end);
    begin = end;
  }
  return lines;
}

bool NumberStart(const std::string& t, size_t i) {
  const auto digit = [&](size_t k) { return k < t.size() && std::isdigit(static_cast<unsigned char>(t[k])); };
  if (digit(i)) return i == 0 || !std::isalnum(static_cast<unsigned char>(t[i - 1]));
  return (t[i] == '-' || t[i] == '+' || t[i] == '.') && digit(i + 1) &&
         (i == 0 || !std::isalnum(static_cast<unsigned char>(t[i - 1])));
}

}  // namespace

std::vector<std::pair<size_t, size_t>> NumberTokens(const std::string& text) {
  std::vector<std::pair<size_t, size_t>> tokens;
  for (size_t i = 0; i < text.size();) {
    if (!NumberStart(text, i)) {
      ++i;
      continue;
    }
    size_t end = i + 1;
    while (end < text.size() && (std::isalnum(static_cast<unsigned char>(text[end])) || text[end] == '.' ||
                                 ((text[end] == '-' || text[end] == '+') && (text[end - 1] == 'e' || text[end - 1] == 'E')))) {
      ++end;
    }
    tokens.emplace_back(i, end);
    i = end;
  }
  return tokens;
}

void Mutator::TextStep(std::string& text, const std::vector<std::string>& others) {
  const auto lines = Lines(text);
  switch (Below(14)) {
    case 0: {  // replace a number with an extreme
      const auto tokens = NumberTokens(text);
      if (tokens.empty()) break;
      const auto [begin, end] = tokens[Below(tokens.size())];
      text.replace(begin, end - begin, ExtremeNumbers()[Below(ExtremeNumbers().size())]);
      break;
    }
    case 1:  // delete a line
      if (!lines.empty()) {
        const auto [begin, end] = lines[Below(lines.size())];
        text.erase(begin, end - begin);
      }
      break;
    case 2:  // duplicate a line
      if (!lines.empty()) {
        const auto [begin, end] = lines[Below(lines.size())];
        text.insert(lines[Below(lines.size())].first, text.substr(begin, end - begin));
      }
      break;
    case 3: {  // delete or duplicate a field (',' separated) or a value ('=')
      if (text.empty()) break;
      const size_t at = Below(text.size());
      const size_t separator = text.find_first_of(",=", at);
      if (separator == std::string::npos) break;
      const size_t next = text.find_first_of(",\n", separator + 1);
      const size_t end = next == std::string::npos ? text.size() : next;
      if (Below(2)) {
        text.erase(separator, end - separator);
      } else {
        text.insert(end, text.substr(separator, end - separator));
      }
      break;
    }
    case 4: {  // odd text at a random place, or replacing a quoted string
      const size_t quote = text.empty() ? std::string::npos : text.find('"', Below(text.size()));
      const size_t close = quote == std::string::npos ? quote : text.find('"', quote + 1);
      if (close != std::string::npos && Below(2)) {
        text.replace(quote + 1, close - quote - 1, OddText(random_));
      } else {
        text.insert(Below(text.size() + 1), OddText(random_));
      }
      break;
    }
    case 5:  // a byte order mark in front
      text.insert(0, "\xEF\xBB\xBF");
      break;
    case 6: {  // line ends: CRLF, CR only, or no final newline
      const size_t kind = Below(3);
      if (kind == 2) {
        if (!text.empty() && text.back() == '\n') text.pop_back();
        break;
      }
      std::string out;
      for (char c : text) out += c == '\n' ? (kind == 0 ? "\r\n" : "\r") : std::string(1, c);
      text = out;
      break;
    }
    case 7:  // truncate
      text.resize(Below(text.size() + 1));
      break;
    case 8:  // flip a bit
      if (!text.empty()) text[Below(text.size())] ^= static_cast<char>(1 << Below(8));
      break;
    case 9: {  // a separator or structural byte
      static const char kBytes[] = {'\n', '\r', ',', '"', '#', '=', '[', ']', '{', '}', '.', '-', 'e', ' ', ':', '|'};
      if (!text.empty()) text[Below(text.size())] = kBytes[Below(sizeof kBytes)];
      break;
    }
    case 10:  // swap two lines
      if (lines.size() >= 2) {
        const auto a = lines[Below(lines.size())], b = lines[Below(lines.size())];
        const std::string la = text.substr(a.first, a.second - a.first), lb = text.substr(b.first, b.second - b.first);
        if (a.first < b.first) {
          text.replace(b.first, lb.size(), la);
          text.replace(a.first, la.size(), lb);
        }
      }
      break;
    case 11:  // a line of another seed
      if (!others.empty()) {
        const std::string& other = others[Below(others.size())];
        const auto other_lines = Lines(other);
        if (!other_lines.empty()) {
          const auto [begin, end] = other_lines[Below(other_lines.size())];
          text.insert(lines.empty() ? 0 : lines[Below(lines.size())].first, other.substr(begin, end - begin));
        }
      }
      break;
    case 12: {  // a number made longer, negative or fractional
      const auto tokens = NumberTokens(text);
      if (tokens.empty()) break;
      const auto [begin, end] = tokens[Below(tokens.size())];
      static const char* kAffixes[] = {"-", "0", "e300", "e-300", "000000000000", ".5", "e+", "_1"};
      const char* affix = kAffixes[Below(8)];
      if (affix[0] == '-') text.insert(begin, affix); else text.insert(end, affix);
      break;
    }
    default: {  // duplicate a chunk (a table, a block of rows)
      if (text.empty()) break;
      const size_t begin = Below(text.size());
      const size_t length = 1 + Below(std::min<size_t>(text.size() - begin, 4096));
      text.insert(Below(text.size() + 1), text.substr(begin, length));
      break;
    }
  }
  if (text.size() > max_bytes) text.resize(max_bytes);
}

std::string Mutator::MutateText(const std::string& input, const std::vector<std::string>& others) {
  std::string text = input;
  const size_t steps = 1 + Below(4);
  for (size_t i = 0; i < steps; ++i) TextStep(text, others);
  return text;
}

namespace {

uint32_t Read32(const std::string& b, size_t at) {
  uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;  // little-endian files on a little-endian host (the seeds are written here)
}
void Write16(std::string& b, size_t at, uint16_t v) {
  if (at + 2 <= b.size()) std::memcpy(b.data() + at, &v, 2);
}
void Write32(std::string& b, size_t at, uint32_t v) {
  if (at + 4 <= b.size()) std::memcpy(b.data() + at, &v, 4);
}

uint32_t Extreme32(std::mt19937_64& random) {
  static const uint32_t kValues[] = {0, 1, 2, 3, 7, 8, 16, 255, 256, 65535, 65536, 0x7fffffff, 0x80000000,
                                     0xffffffff, 0xfffffffe, 1u << 20, 1u << 24, 1u << 30};
  return random() % 4 == 0 ? static_cast<uint32_t>(random()) : kValues[random() % (sizeof kValues / 4)];
}

}  // namespace

void Mutator::TiffStep(std::string& b) {
  // The first IFD of a classic little-endian TIFF: entries of 12 bytes (tag,
  // type, count, value/offset) after a 2-byte entry count.
  const bool classic = b.size() >= 8 && b.compare(0, 4, "II*\0", 4) == 0;
  const size_t ifd = classic ? Read32(b, 4) : 0;  // size_t: an offset of 0xffffffff must not wrap
  const size_t entries =
      classic && ifd + 2 <= b.size() ? static_cast<uint8_t>(b[ifd]) | (static_cast<uint8_t>(b[ifd + 1]) << 8) : 0;
  const size_t usable = entries > 0 && ifd + 2 + 12 * entries <= b.size() ? entries : 0;
  switch (Below(usable ? 8 : 4)) {
    case 0:  // flip a bit
      if (!b.empty()) b[Below(b.size())] ^= static_cast<char>(1 << Below(8));
      break;
    case 1:  // an extreme 32-bit value anywhere
      if (b.size() >= 4) Write32(b, Below(b.size() - 3), Extreme32(random_));
      break;
    case 2:  // truncate
      b.resize(Below(b.size() + 1));
      break;
    case 3: {  // delete or duplicate a chunk
      if (b.empty()) break;
      const size_t at = Below(b.size());
      const size_t length = 1 + Below(std::min<size_t>(b.size() - at, 256));
      if (Below(2)) b.erase(at, length); else b.insert(Below(b.size() + 1), b.substr(at, length));
      break;
    }
    default: {  // one IFD entry: its count, value/offset, type, or tag
      const size_t entry = ifd + 2 + 12 * Below(usable);
      switch (Below(4)) {
        case 0: Write32(b, entry + 4, Extreme32(random_)); break;                         // count
        case 1: Write32(b, entry + 8, Extreme32(random_)); break;                         // value or offset
        case 2: Write16(b, entry + 2, static_cast<uint16_t>(Below(20))); break;           // type (1..18 valid)
        default: Write16(b, entry, static_cast<uint16_t>(Extreme32(random_) & 0xffff)); // tag
      }
    }
  }
  if (b.size() > max_bytes) b.resize(max_bytes);
}

std::string Mutator::MutateTiff(const std::string& input) {
  std::string bytes = input;
  const size_t steps = 1 + Below(3);
  for (size_t i = 0; i < steps; ++i) TiffStep(bytes);
  return bytes;
}

}  // namespace platemeter::fuzz
