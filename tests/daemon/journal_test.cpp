// Message priorities for the journal (journal.hpp): passed on to the journal's stream,
// stripped from every other stream, and the journal's stream recognised by JOURNAL_STREAM.
#include "hapticd/daemon/journal.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdlib>
#include <ostream>
#include <sstream>
#include <string>

#include "scratch_dir.hpp"

namespace hapticd::daemon {
namespace {

/// `text` through a filter that is then destroyed, as at the end of a process.
std::string filtered(const std::string& text, bool keep) {
    std::ostringstream target;
    {
        PriorityLineFilter filter(target.rdbuf(), keep);
        std::ostream out(&filter);
        out << text << std::flush;
    }
    return target.str();
}

TEST(PriorityLineFilter, StripsTheLeadingPriorityOfEveryLineForATerminal) {
    EXPECT_EQ(filtered("<4>hapticd: fault jump, force zeroed\n<6>hapticd: t 1 s\n", false),
              "hapticd: fault jump, force zeroed\nhapticd: t 1 s\n");
    EXPECT_EQ(filtered(std::string(priority::err) + "a\n" + priority::notice + "b\n" +
                           priority::info + "c\n" + priority::warning + "d",
                       false),
              "a\nb\nc\nd");
}

TEST(PriorityLineFilter, KeepsThemForTheJournal) {
    const std::string text = "<4>hapticd: fault jump\n<6>hapticd: t 1 s\n";
    EXPECT_EQ(filtered(text, true), text);
}

TEST(PriorityLineFilter, LeavesEverythingThatIsNotALeadingPriorityAlone) {
    for (const std::string text :
         {"hapticd: [4] <4> in the middle\n", "<12>two digits\n", "<x>not a digit\n", "<4\n", "<\n",
          "<", "\n\n<4 >\n", "plain", "x<4>y\n"}) {
        EXPECT_EQ(filtered(text, false), text) << text;
    }
    EXPECT_EQ(filtered("\n<5>after an empty line\n", false), "\nafter an empty line\n");
}

TEST(PriorityLineFilter, APrefixSplitAcrossWritesIsStillOne) {
    std::ostringstream target;
    PriorityLineFilter filter(target.rdbuf(), false);
    std::ostream out(&filter);
    out << "<" << std::flush << "4" << std::flush << ">fault\n" << std::flush;
    EXPECT_EQ(target.str(), "fault\n");
}

class JournalStream : public ::testing::Test {
  protected:
    void SetUp() override {
        if (const char* old = std::getenv("JOURNAL_STREAM")) saved_ = old, had_ = true;
        fd_ = ::open(dir_.file("stream").c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
        ASSERT_GE(fd_, 0);
    }
    void TearDown() override {
        ::close(fd_);
        if (had_) {
            ::setenv("JOURNAL_STREAM", saved_.c_str(), 1);
        } else {
            ::unsetenv("JOURNAL_STREAM");
        }
    }
    std::string identity_of(int fd) const {
        struct stat st {};
        EXPECT_EQ(::fstat(fd, &st), 0);
        return std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
    }
    const hapticd::testing::ScratchDir dir_;
    int fd_ = -1;
    std::string saved_;
    bool had_ = false;
};

TEST_F(JournalStream, IsTheStreamWhoseDeviceAndInodeJournalStreamNames) {
    ::setenv("JOURNAL_STREAM", identity_of(fd_).c_str(), 1);
    EXPECT_TRUE(is_journal_stream(fd_));
    const int other = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    ASSERT_GE(other, 0);
    EXPECT_FALSE(is_journal_stream(other));  // stderr redirected by hand after systemd set it
    ::close(other);
    ::setenv("JOURNAL_STREAM", "0:0", 1);
    EXPECT_FALSE(is_journal_stream(fd_));
    ::setenv("JOURNAL_STREAM", "garbage", 1);
    EXPECT_FALSE(is_journal_stream(fd_));
    ::unsetenv("JOURNAL_STREAM");
    EXPECT_FALSE(is_journal_stream(fd_));
    EXPECT_FALSE(is_journal_stream(-1));
}

}  // namespace
}  // namespace hapticd::daemon
