// docs/protocol.md's worked examples are the encoder's output, byte for byte: the generated
// section between the markers must equal what `protocol_corpus --markdown` prints now.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "protocol_examples.hpp"

namespace hapticd::device::protocol {
namespace {

std::string read_doc() {
    std::ifstream in(HAPTICD_PROTOCOL_DOC);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
}

TEST(ProtocolDocs, WorkedExamplesAreTheEncodersOutput) {
    const std::string doc = read_doc();
    ASSERT_FALSE(doc.empty()) << HAPTICD_PROTOCOL_DOC;
    const std::size_t begin = doc.find(examples::kMarkdownBegin);
    const std::size_t end = doc.find(examples::kMarkdownEnd);
    ASSERT_NE(begin, std::string::npos);
    ASSERT_NE(end, std::string::npos);
    const std::size_t body = begin + std::string(examples::kMarkdownBegin).size() + 2;
    EXPECT_EQ(doc.substr(body, end - body), examples::markdown())
        << "regenerate section 8 with: protocol_corpus --markdown";
}

TEST(ProtocolDocs, EveryMessageTypeHasAnExample) {
    int seen[256] = {};
    for (const examples::Example& e : examples::frame_examples()) {
        Message message;
        ASSERT_EQ(decode(e.bytes, message), Error::none) << e.name;
        ++seen[static_cast<std::uint8_t>(type_of(message))];
    }
    for (int type = 0; type < 256; ++type) {
        if (is_message_type(static_cast<std::uint8_t>(type))) {
            EXPECT_GT(seen[type], 0) << type;
        }
    }
}

}  // namespace
}  // namespace hapticd::device::protocol
