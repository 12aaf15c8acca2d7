#include "animation_pointers.hpp"

#include <cstring>
#include <regex>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace crowd {

namespace {

constexpr char kExtension[] = "KHR_animation_pointer";
constexpr uint32_t kJsonChunk = 0x4E4F534A, kGlbHeader = 12, kChunkHeader = 8;

uint32_t read_u32(const uint8_t* at) {
  uint32_t value;
  std::memcpy(&value, at, sizeof value);  // GLB is little-endian, as are the crowd's targets
  return value;
}

void write_u32(std::vector<uint8_t>& out, uint32_t value) {
  const auto* bytes = reinterpret_cast<const uint8_t*>(&value);
  out.insert(out.end(), bytes, bytes + sizeof value);
}

// object[key], or null when object is no object or has no such member (never throws: the file
// is untrusted input).
const nlohmann::json* member(const nlohmann::json& object, const char* key) {
  if (!object.is_object()) return nullptr;
  const auto found = object.find(key);
  return found == object.end() ? nullptr : &*found;
}

std::string string_member(const nlohmann::json* object, const char* key) {
  const nlohmann::json* value = object ? member(*object, key) : nullptr;
  return value && value->is_string() ? value->get<std::string>() : std::string();
}

// Rewrites the pointer channels of `document` (an object); false when it has none.
bool resolve_in(nlohmann::json& document) {
  // At most 9 digits: no index overflows, and no real file has a billion nodes.
  static const std::regex node_pointer("/nodes/([0-9]{1,9})/(translation|rotation|scale|weights)");
  bool changed = false;
  if (!document.contains("animations") || !document["animations"].is_array()) return false;
  for (nlohmann::json& animation : document["animations"]) {
    if (!animation.is_object() || !animation.contains("channels") || !animation["channels"].is_array()) continue;
    for (nlohmann::json& channel : animation["channels"]) {
      if (!channel.is_object() || !channel.contains("target")) continue;
      nlohmann::json& target = channel["target"];
      if (!target.is_object() || target.contains("node") || string_member(&target, "path") != "pointer") continue;
      const nlohmann::json* extensions = member(target, "extensions");
      const std::string pointer = string_member(extensions ? member(*extensions, kExtension) : nullptr, "pointer");
      std::smatch match;
      if (std::regex_match(pointer, match, node_pointer)) {
        target["node"] = std::stol(match[1].str());
        target["path"] = match[2].str();
      } else {
        target["node"] = -1;  // animates no node: kept, and skipped by the crowd
      }
      changed = true;
    }
  }
  return changed;
}

std::vector<uint8_t> resolve_json(const char* text, size_t size) {
  nlohmann::json document = nlohmann::json::parse(text, text + size, nullptr, /*allow_exceptions=*/false);
  if (document.is_discarded() || !document.is_object() || !resolve_in(document)) return {};
  const std::string dumped = document.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return std::vector<uint8_t>(dumped.begin(), dumped.end());
}

}  // namespace

std::vector<uint8_t> resolve_animation_pointers(const uint8_t* bytes, size_t size) {
  const char* text = reinterpret_cast<const char*>(bytes);
  if (!is_glb(bytes, size)) {
    if (std::string_view(text, size).find(kExtension) == std::string_view::npos) return {};
    return resolve_json(text, size);
  }
  if (size < kGlbHeader + kChunkHeader || read_u32(bytes + kGlbHeader + 4) != kJsonChunk) return {};
  const uint32_t json_length = read_u32(bytes + kGlbHeader);
  const size_t json_end = kGlbHeader + kChunkHeader + static_cast<size_t>(json_length);
  if (json_end > size) return {};
  const char* json = text + kGlbHeader + kChunkHeader;
  if (std::string_view(json, json_length).find(kExtension) == std::string_view::npos) return {};
  std::vector<uint8_t> resolved = resolve_json(json, json_length);
  if (resolved.empty()) return {};
  resolved.resize((resolved.size() + 3) / 4 * 4, ' ');  // chunks are 4-byte aligned, JSON padded with spaces
  std::vector<uint8_t> out;
  out.reserve(kGlbHeader + kChunkHeader + resolved.size() + (size - json_end));
  out.insert(out.end(), bytes, bytes + 8);  // magic and version
  write_u32(out, static_cast<uint32_t>(kGlbHeader + kChunkHeader + resolved.size() + (size - json_end)));
  write_u32(out, static_cast<uint32_t>(resolved.size()));
  write_u32(out, kJsonChunk);
  out.insert(out.end(), resolved.begin(), resolved.end());
  out.insert(out.end(), bytes + json_end, bytes + size);  // the binary chunk as it was
  return out;
}

}  // namespace crowd
