// Replays a libFuzzer corpus through LLVMFuzzerTestOneInput without libFuzzer, so that a plain
// (GCC) build runs every fuzzer's seeds and invariants in ctest (CMakeLists.txt here links it
// with each of fuzz/*_fuzz.cpp). Each seed is also replayed with a few hundred deterministic
// single-byte mutations, a cheap stand-in for the fuzzer's first steps.
// Usage: <name>_fuzz_replay CORPUS_DIR...
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

int main(int argc, char** argv) {
    if (argc < 2) {
        std::cerr << "usage: " << argv[0] << " CORPUS_DIR...\n";
        return 2;
    }
    std::size_t files = 0;
    std::size_t runs = 0;
    std::uint64_t state = 0x2545F4914F6CDD1Dull;
    auto next = [&state]() {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        return state;
    };
    for (int i = 1; i < argc; ++i) {
        for (const auto& entry : std::filesystem::directory_iterator(argv[i])) {
            if (!entry.is_regular_file()) continue;
            std::ifstream in(entry.path(), std::ios::binary);
            std::vector<std::uint8_t> input((std::istreambuf_iterator<char>(in)),
                                            std::istreambuf_iterator<char>());
            ++files;
            LLVMFuzzerTestOneInput(input.data(), input.size());
            ++runs;
            for (int m = 0; m < 300 && !input.empty(); ++m) {
                std::vector<std::uint8_t> mutated = input;
                const std::uint64_t r = next();
                mutated[r % mutated.size()] ^= static_cast<std::uint8_t>(1u + (r >> 32) % 255u);
                if (m % 3 == 0)
                    mutated.resize(static_cast<std::size_t>(next() % (mutated.size() + 1)));
                LLVMFuzzerTestOneInput(mutated.data(), mutated.size());
                ++runs;
            }
        }
    }
    std::cout << "replayed " << files << " corpus files, " << runs << " inputs\n";
    return files > 0 ? 0 : 1;
}
