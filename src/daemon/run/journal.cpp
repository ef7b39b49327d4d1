#include "hapticd/daemon/journal.hpp"

#include <sys/stat.h>

#include <cctype>
#include <cstdlib>
#include <string>

namespace hapticd::daemon {

bool is_journal_stream(int fd) {
    const char* stream = std::getenv("JOURNAL_STREAM");
    if (stream == nullptr) return false;
    struct stat st {};
    if (::fstat(fd, &st) != 0) return false;
    return std::string(stream) == std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
}

PriorityLineFilter::~PriorityLineFilter() {
    if (pending_size_ > 0) flush_pending();
}

bool PriorityLineFilter::flush_pending() {
    const auto n = static_cast<std::streamsize>(pending_size_);
    pending_size_ = 0;
    return target_->sputn(pending_.data(), n) == n;
}

PriorityLineFilter::int_type PriorityLineFilter::overflow(int_type c) {
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    const char ch = traits_type::to_char_type(c);
    if (!keep_ && line_start_) {
        // "<", "<4", "<4>": a prefix so far; anything else ends it as text.
        pending_[pending_size_++] = ch;
        const bool prefix_so_far =
            (pending_size_ == 1 && ch == '<') ||
            (pending_size_ == 2 && std::isdigit(static_cast<unsigned char>(ch)) != 0) ||
            (pending_size_ == 3 && ch == '>');
        if (prefix_so_far && pending_size_ < pending_.size()) return c;
        line_start_ = false;
        if (prefix_so_far) {
            pending_size_ = 0;  // the whole prefix: dropped
            return c;
        }
        if (!flush_pending()) return traits_type::eof();
        if (ch == '\n') line_start_ = true;
        return c;
    }
    if (traits_type::eq_int_type(target_->sputc(ch), traits_type::eof())) {
        return traits_type::eof();
    }
    line_start_ = ch == '\n';
    return c;
}

int PriorityLineFilter::sync() {
    // A partial prefix stays pending until the line says whether it is one.
    return target_->pubsync();
}

}  // namespace hapticd::daemon
