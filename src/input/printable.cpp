#include "hapticd/input/printable.hpp"

namespace hapticd::input {
namespace {

constexpr bool is_c0_or_del(unsigned char c) noexcept { return c < 0x20 || c == 0x7F; }
constexpr bool is_c1_second_byte(unsigned char c) noexcept { return c >= 0x80 && c <= 0x9F; }
constexpr unsigned char kC1Lead = 0xC2;

std::string hex_escape(const char* prefix, unsigned char c) {
    constexpr std::string_view kDigits = "0123456789abcdef";
    return std::string(prefix) + kDigits[c >> 4U] + kDigits[c & 0x0FU];
}

}  // namespace

std::size_t find_control(std::string_view text) noexcept {
    for (std::size_t i = 0; i < text.size(); ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (is_c0_or_del(c)) return i;
        if (c == kC1Lead && i + 1 < text.size() &&
            is_c1_second_byte(static_cast<unsigned char>(text[i + 1]))) {
            return i;
        }
    }
    return std::string_view::npos;
}

std::string printable(std::string_view text) {
    std::string out;
    out.reserve(text.size());
    for (std::size_t i = 0; i < text.size(); ++i) {
        const auto c = static_cast<unsigned char>(text[i]);
        if (is_c0_or_del(c)) {
            out += hex_escape("\\x", c);
        } else if (c == kC1Lead && i + 1 < text.size() &&
                   is_c1_second_byte(static_cast<unsigned char>(text[i + 1]))) {
            out += hex_escape("\\u00", static_cast<unsigned char>(text[++i]));
        } else {
            out += text[i];
        }
    }
    return out;
}

PrintableFilter::~PrintableFilter() {
    if (after_c2_) target_->sputc(static_cast<char>(kC1Lead));  // text after all
}

bool PrintableFilter::put(std::string_view text) {
    return target_->sputn(text.data(), static_cast<std::streamsize>(text.size())) ==
           static_cast<std::streamsize>(text.size());
}

PrintableFilter::int_type PrintableFilter::overflow(int_type ch) {
    if (traits_type::eq_int_type(ch, traits_type::eof())) return traits_type::not_eof(ch);
    const auto c = static_cast<unsigned char>(traits_type::to_char_type(ch));
    if (after_c2_) {
        after_c2_ = false;
        if (is_c1_second_byte(c)) return put(hex_escape("\\u00", c)) ? ch : traits_type::eof();
        if (!put(std::string_view("\xC2", 1))) return traits_type::eof();
    }
    if (c == kC1Lead) {
        after_c2_ = true;
        return ch;
    }
    if (is_c0_or_del(c) && c != '\n' && c != '\t') {
        return put(hex_escape("\\x", c)) ? ch : traits_type::eof();
    }
    return traits_type::eq_int_type(target_->sputc(static_cast<char>(c)), traits_type::eof())
               ? traits_type::eof()
               : ch;
}

int PrintableFilter::sync() { return target_->pubsync(); }

}  // namespace hapticd::input
