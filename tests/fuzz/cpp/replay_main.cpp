// Runs a fuzz harness without libFuzzer, so that `make test` (g++, ctest) and `make sanitize`
// replay every saved crash (tests/fuzz/crashes/<harness>/) and a fixed set of pseudo-random
// inputs through it:
//   animlod_replay_<harness> [--random N] [FILE or FOLDER]...
// A broken invariant aborts (the test fails); a missing folder counts as empty.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

namespace {

void run_file(const std::filesystem::path& path) {
  std::ifstream stream(path, std::ios::binary);
  const std::vector<char> bytes((std::istreambuf_iterator<char>(stream)), std::istreambuf_iterator<char>());
  std::fprintf(stderr, "replay %s (%zu bytes)\n", path.string().c_str(), bytes.size());
  LLVMFuzzerTestOneInput(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
}

// xorshift64: the same inputs on every machine.
uint64_t next(uint64_t& state) {
  state ^= state << 13;
  state ^= state >> 7;
  state ^= state << 17;
  return state;
}

}  // namespace

int main(int argc, char** argv) {
  size_t files = 0, random_inputs = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    if (argument == "--random" && i + 1 < argc) {
      random_inputs = std::strtoul(argv[++i], nullptr, 10);
      continue;
    }
    const std::filesystem::path path(argument);
    if (std::filesystem::is_directory(path)) {
      for (const auto& entry : std::filesystem::directory_iterator(path))
        if (entry.is_regular_file() && entry.path().filename().string()[0] != '.') {
          run_file(entry.path());
          ++files;
        }
    } else if (std::filesystem::is_regular_file(path)) {
      run_file(path);
      ++files;
    }
  }
  uint64_t state = 0x9E3779B97F4A7C15ull;
  std::vector<uint8_t> bytes;
  for (size_t n = 0; n < random_inputs; ++n) {
    bytes.resize(next(state) % 4096);
    for (uint8_t& byte : bytes) byte = static_cast<uint8_t>(next(state) >> 56);
    LLVMFuzzerTestOneInput(bytes.data(), bytes.size());
  }
  std::printf("replayed %zu files and %zu pseudo-random inputs\n", files, random_inputs);
  return 0;
}
