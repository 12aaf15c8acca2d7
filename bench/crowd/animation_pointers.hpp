// KHR_animation_pointer channels for the crowd's loader. Debian's tinygltf (2.7) requires a
// channel target's node and drops, while parsing, every channel that has none, as a pointer
// channel does: joints animated through pointers would stand still (or a clip would seem to move
// nothing). The crowd therefore resolves the pointers in the JSON before tinygltf reads it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace crowd {

// Whether `bytes` are a GLB (its magic, whatever the file's name: a VRM avatar's is .vrm) rather
// than glTF JSON.
inline bool is_glb(const uint8_t* bytes, size_t size) { return size >= 4 && std::memcmp(bytes, "glTF", 4) == 0; }

// `bytes` (a GLB or glTF JSON) with every KHR_animation_pointer channel that names a node's
// translation, rotation, scale or weights made a channel of that node, and every other pointer
// channel (a material's colour, a light) a channel of node -1 with path "pointer", which
// tinygltf keeps, so that channel indices stay the file's. Empty when there is nothing to
// rewrite: no pointer channel, or JSON or a GLB layout that does not parse (tinygltf then reads
// the original and reports what it finds).
std::vector<uint8_t> resolve_animation_pointers(const uint8_t* bytes, size_t size);

}  // namespace crowd
