// Control characters in text a client or a file supplied: found, and written out before the
// journal or a terminal shows them (issue 28: a newline in a path wrote the client's own
// journal lines at priority <0>; a scene name cleared other operators' screens).
#include "hapticd/input/printable.hpp"

#include <gtest/gtest.h>

#include <sstream>
#include <string>

namespace hapticd::input {
namespace {

using namespace std::string_literals;

TEST(Printable, FindsEveryKindOfControlCharacter) {
    EXPECT_EQ(find_control("take1.csv"), std::string_view::npos);
    EXPECT_EQ(find_control("Wand – grün"), std::string_view::npos);  // UTF-8 text is text
    EXPECT_EQ(find_control("a\nb"), 1u);
    EXPECT_EQ(find_control("ab\tc"), 2u);
    EXPECT_EQ(find_control("x\x1b[2J"), 1u);  // ESC: clear the screen
    EXPECT_EQ(find_control("x\x7f"), 1u);     // DEL
    EXPECT_EQ(find_control("xy\xc2\x9b"
                           "2J"),
              2u);                                                // C1 CSI, as UTF-8
    EXPECT_EQ(find_control("\xc2\xa0"), std::string_view::npos);  // no-break space: text
    EXPECT_EQ(find_control("x\0y"s), 1u);
}

TEST(Printable, WritesControlCharactersOutAndKeepsTheRest) {
    EXPECT_EQ(printable("take1.csv"), "take1.csv");
    EXPECT_EQ(printable("a.csv\n<0>hapticd: fault"), "a.csv\\x0a<0>hapticd: fault");
    EXPECT_EQ(printable("\x1b]0;root\x07"), "\\x1b]0;root\\x07");
    EXPECT_EQ(printable("\xc2\x9b"
                        "2J grün"),
              "\\u009b2J grün");
    EXPECT_EQ(printable("tab\there\r"), "tab\\x09here\\x0d");
    EXPECT_EQ(printable("end\xc2"), "end\xc2");  // a lone lead byte at the end is kept
    EXPECT_EQ(printable("\0\x7f"s), "\\x00\\x7f");
}

TEST(Printable, TheTerminalFilterKeepsLinesAndTabsOnly) {
    std::ostringstream target;
    {
        PrintableFilter filter(target.rdbuf());
        std::ostream out(&filter);
        out << "scene \"\x1b[2J\x1b[Hstate disabled\" from /x\n\tgrün\xc2\x9b"
               "1m\r\n";
        out << "ends on a lead byte \xc2";
    }
    EXPECT_EQ(target.str(),
              "scene \"\\x1b[2J\\x1b[Hstate disabled\" from /x\n\tgrün\\u009b1m\\x0d\n"
              "ends on a lead byte \xc2");
}

}  // namespace
}  // namespace hapticd::input
