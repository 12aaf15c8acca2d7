// Decimates a procedural sphere of about 200k triangles to 20k with OpenMesh's Decimater and
// ModQuadric, and prints one Markdown table row: label, faces before/after, seconds.
// usage: openmesh_decimater_bench LABEL
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

using Mesh = OpenMesh::TriMesh_ArrayKernelT<>;

// A latitude-longitude sphere with wobbly radius (so that collapses have different costs).
static Mesh make_sphere(int rings, int segments) {
  Mesh mesh;
  std::vector<Mesh::VertexHandle> grid;
  const Mesh::VertexHandle north = mesh.add_vertex(Mesh::Point(0, 1, 0));
  for (int r = 1; r < rings; ++r) {
    const float theta = float(M_PI) * r / rings;
    for (int s = 0; s < segments; ++s) {
      const float phi = 2.0f * float(M_PI) * s / segments;
      const float radius = 1.0f + 0.05f * std::sin(5 * theta) * std::cos(7 * phi);
      grid.push_back(mesh.add_vertex(
          Mesh::Point(radius * std::sin(theta) * std::cos(phi), radius * std::cos(theta), radius * std::sin(theta) * std::sin(phi))));
    }
  }
  const Mesh::VertexHandle south = mesh.add_vertex(Mesh::Point(0, -1, 0));
  auto at = [&](int r, int s) { return grid[(r - 1) * segments + (s % segments)]; };
  for (int s = 0; s < segments; ++s) {
    mesh.add_face(north, at(1, s + 1), at(1, s));
    mesh.add_face(south, at(rings - 1, s), at(rings - 1, s + 1));
    for (int r = 1; r < rings - 1; ++r) {
      mesh.add_face(at(r, s), at(r, s + 1), at(r + 1, s + 1));
      mesh.add_face(at(r, s), at(r + 1, s + 1), at(r + 1, s));
    }
  }
  return mesh;
}

int main(int argc, char** argv) {
  const char* label = argc > 1 ? argv[1] : "OpenMesh";
  Mesh mesh = make_sphere(317, 317);  // 2 * 317 * 316 = 200,344 triangles
  const size_t before = mesh.n_faces();
  const auto start = std::chrono::steady_clock::now();
  OpenMesh::Decimater::DecimaterT<Mesh> decimater(mesh);
  OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
  decimater.add(quadric);
  decimater.initialize();
  decimater.decimate_to_faces(0, before / 10);
  mesh.garbage_collection();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("| %s | %zu | %zu | %.2f |\n", label, before, mesh.n_faces(), seconds);
  return 0;
}
