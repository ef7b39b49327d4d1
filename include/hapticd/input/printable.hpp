// Text that came from a client or a file, made safe to show (docs/control.md, "What a client
// supplies"). In the journal a newline in a client's string would start a line of the
// client's own, with a "<0>" priority of its choosing; on a terminal an escape sequence
// clears the screen, moves the cursor or retitles the window. Control characters are the
// carriers of both, and no name, path or message of ours needs one.
#pragma once

#include <array>
#include <cstddef>
#include <streambuf>
#include <string>
#include <string_view>

namespace hapticd::input {

/// The offset of the first control character in `text`: C0 (0x00-0x1F, tab and newline
/// included), DEL (0x7F) or C1 (U+0080-U+009F, UTF-8 0xC2 0x80-0x9F); npos when none is.
std::size_t find_control(std::string_view text) noexcept;

/// `text` with each control character written out: C0 and DEL as \xNN, C1 as \u00NN. The
/// rest (UTF-8 text included) is kept. For a journal line: one message, one line.
std::string printable(std::string_view text);

/// Passes text on to `target` with control characters written out as printable() writes
/// them, but newline and tab: for a terminal program's stdout and stderr, which show what a
/// daemon or a file said (hapticctl).
class PrintableFilter : public std::streambuf {
  public:
    explicit PrintableFilter(std::streambuf* target) : target_(target) {}
    ~PrintableFilter() override;
    PrintableFilter(const PrintableFilter&) = delete;
    PrintableFilter& operator=(const PrintableFilter&) = delete;

  protected:
    int_type overflow(int_type c) override;
    int sync() override;

  private:
    bool put(std::string_view text);
    std::streambuf* target_;
    bool after_c2_ = false;  ///< the last byte was 0xC2, which may begin a C1 character
};

}  // namespace hapticd::input
