// libFuzzer: bytes -> splitMultipart (the upload route's parser) via a body file in a
// per-process temp folder; every part file it keeps is checked to lie in the output folder, and
// after a throw the folder must be empty (nothing is left behind on an error path).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "server/api/multipart.hpp"
#include "server/http/http_types.hpp"

namespace fs = std::filesystem;

namespace {

const fs::path& workDir() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() / ("rover-fuzz-multipart-" + std::to_string(::getpid()));
    fs::remove_all(d);
    fs::create_directories(d / "parts");
    std::atexit([] {
      std::error_code ec;
      fs::remove_all(workDir(), ec);
    });
    return d;
  }();
  return dir;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const fs::path body = workDir() / "body";
  const fs::path parts = workDir() / "parts";
  {
    std::ofstream out(body, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  // The boundary a client would declare: "fuzz" (the seeds and the dictionary use it).
  bool threw = false;
  try {
    const auto result = rover::api::splitMultipart(body.string(), "fuzz", parts.string());
    for (const auto& p : result) {
      if (p.filename.empty()) {
        if (!p.path.empty() || p.value.size() > rover::api::MultipartLimits{}.maxFieldBytes) std::abort();
      } else if (fs::path(p.path).parent_path() != parts) {
        std::abort();
      }
    }
  } catch (const rover::http::ApiError& e) {
    threw = true;
    if (e.field().empty()) std::abort();  // every refusal names its field
  }
  if (threw && !fs::is_empty(parts)) std::abort();  // an error path left a part file behind
  std::error_code ec;
  for (const auto& f : fs::directory_iterator(parts, ec)) fs::remove_all(f.path(), ec);
  return 0;
}
