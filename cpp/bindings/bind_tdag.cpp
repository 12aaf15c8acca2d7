// Bindings of animlod/tdag.hpp, tdag_affine.hpp and tdag_player.hpp: the TDAG, its cuts, the
// player and the affine split. Thin: check shapes, convert, call with the GIL released.
#include <cstring>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "animlod/tdag.hpp"
#include "animlod/tdag_affine.hpp"
#include "animlod/tdag_player.hpp"
#include "array_checks.hpp"
#include "enum_names.hpp"
#include "numpy_from_vector.hpp"
#include "released_call.hpp"

namespace animlod::bindings {

namespace {

ApproximationLevel level_from(int level) {
  if (level < 1 || level > 3) throw py::value_error("level: expected 1, 2 or 3, got " + std::to_string(level));
  return static_cast<ApproximationLevel>(level);
}

AnimatedMeshView mesh_view(const FloatArray& frames, const IndexArray& faces) {
  return {frames.data(), faces.data(), static_cast<size_t>(frames.shape(0)), static_cast<size_t>(frames.shape(1)),
          static_cast<size_t>(faces.shape(0))};
}

ViewTolerance view_from(const std::vector<double>& camera, double pixels, double focal_pixels) {
  if (camera.size() != 3)
    throw py::value_error("camera: expected 3 coordinates, got " + std::to_string(camera.size()));
  ViewTolerance view;
  for (int k = 0; k < 3; ++k) view.camera[k] = camera[static_cast<size_t>(k)];
  view.pixels = pixels;
  view.focal_pixels = focal_pixels;
  return view;
}

py::dict mesh_to_dict(TdagMesh&& mesh) {
  const auto vertices = static_cast<py::ssize_t>(mesh.nodes.size());
  const auto faces = static_cast<py::ssize_t>(mesh.faces.size() / 3);
  py::dict out;
  out["frame"] = mesh.frame;
  out["cut_frame"] = mesh.cut_frame;
  out["residual_frame"] = mesh.residual_frame;
  out["error_bound"] = mesh.error_bound;
  out["positions"] = numpy_from_vector(std::move(mesh.positions), {vertices, 3});
  out["faces"] = numpy_from_vector(std::move(mesh.faces), {faces, 3});
  out["nodes"] = numpy_from_vector(std::move(mesh.nodes), {vertices});
  return out;
}

py::dict stats_to_dict(const PlayerLevelStats& s) {
  py::dict out;
  out["mean_seconds"] = s.mean_seconds;
  out["max_seconds"] = s.max_seconds;
  out["mean_error"] = s.mean_error;
  out["max_error"] = s.max_error;
  out["mean_vertices"] = s.mean_vertices;
  out["mean_faces"] = s.mean_faces;
  out["median_seconds"] = s.median_seconds;
  return out;
}

py::tuple build_py(const FloatArray& frames, const py::array& face_indices, const TdagOptions& options,
                   const std::optional<py::function>& progress) {
  require_shape(frames, "frames", {-1, -1, 3}, "(F, V, 3)");
  const IndexArray faces = index_array(face_indices, "faces");
  require_shape(faces, "faces", {-1, 3}, "(M, 3)");
  TdagOptions copy = options;
  copy.progress = progress_callback(progress);
  TemporalDag dag;
  TdagBuildReport report;
  call_released([&] { return build_temporal_dag(mesh_view(frames, faces), copy, dag, &report); });
  const auto frame_count = static_cast<py::ssize_t>(report.collapse_counts.size());
  const auto collapse_count = static_cast<py::ssize_t>(report.max_cost.size());
  py::dict out;
  out["collapse_counts"] = numpy_from_vector(std::move(report.collapse_counts), {frame_count});
  out["max_cost"] = numpy_from_vector(std::move(report.max_cost), {collapse_count});
  out["use_counts"] = numpy_from_vector(std::move(report.use_counts), {collapse_count});
  out["seconds_affine"] = report.seconds_affine;
  out["seconds_hierarchy"] = report.seconds_hierarchy;
  out["seconds_fields"] = report.seconds_fields;
  return py::make_tuple(dag, out);
}

py::dict affine_split_py(const FloatArray& frames, const std::string& base) {
  require_shape(frames, "frames", {-1, -1, 3}, "(F, V, 3)");
  const AnimatedMeshView mesh{frames.data(), nullptr, static_cast<size_t>(frames.shape(0)),
                              static_cast<size_t>(frames.shape(1)), 0};
  AffineSplit split;
  const AffineBase b = enum_from_name<AffineBase>(base, "base");
  call_released([&] { return affine_split(mesh, b, split); });
  const py::ssize_t f = frames.shape(0), v = frames.shape(1);
  py::dict out;
  out["maps"] = numpy_from_vector(std::move(split.maps), {f, 3, 4});
  out["residuals"] = numpy_from_vector(std::move(split.residuals), {f, v, 3});
  out["translation_only"] = numpy_from_vector(std::move(split.translation_only), {f}).attr("view")("bool");
  return out;
}

void check_frame(const TemporalDag& dag, int32_t frame) {
  if (dag.empty()) throw py::value_error("TemporalDag: empty");
  if (frame < 0 || static_cast<size_t>(frame) >= dag.frame_count())
    throw py::value_error("frame: " + std::to_string(frame) + " outside [0, " + std::to_string(dag.frame_count()) + ")");
}

void check_collapse(const TemporalDag& dag, int64_t c) {
  if (c < 0 || static_cast<size_t>(c) >= dag.collapse_count())
    throw py::value_error("collapse: " + std::to_string(c) + " outside [0, " + std::to_string(dag.collapse_count()) + ")");
}

}  // namespace

void bind_tdag(py::module_& m) {
  py::class_<TemporalDag>(m, "TemporalDag", "A TDAG (animlod/tdag.hpp): immutable; copies share the data.")
      .def_property_readonly("frame_count", &TemporalDag::frame_count)
      .def_property_readonly("vertex_count", &TemporalDag::vertex_count)
      .def_property_readonly("face_count", &TemporalDag::face_count)
      .def_property_readonly("collapse_count", &TemporalDag::collapse_count)
      .def_property_readonly("node_count", &TemporalDag::node_count)
      .def_property_readonly("governing", [](const TemporalDag& d) { return enum_name(d.governing()); })
      .def_property_readonly("affine_base", [](const TemporalDag& d) { return enum_name(d.affine_base()); })
      .def_property_readonly(
          "faces",
          [](const TemporalDag& d) {
            std::vector<int32_t> faces(d.faces(), d.faces() + d.face_count() * 3);
            return numpy_from_vector(std::move(faces), {static_cast<py::ssize_t>(d.face_count()), 3});
          },
          "(M, 3) int32 faces over the TDAG's vertices (a copy)")
      .def_property_readonly(
          "two_sided",
          [](const TemporalDag& d) {
            py::array_t<bool> flags(static_cast<py::ssize_t>(d.face_count()));
            auto out = flags.mutable_unchecked<1>();
            for (py::ssize_t f = 0; f < out.shape(0); ++f) out(f) = d.two_sided(static_cast<size_t>(f));
            return flags;
          },
          "(M,) bool: faces the input also held turned over (a two-sided sheet); cuts hand out their backs "
          "beside them, after the other faces")
      .def_property_readonly(
          "input_points",
          [](const TemporalDag& d) {
            std::vector<int32_t> p(d.input_points(), d.input_points() + d.input_vertex_count());
            return numpy_from_vector(std::move(p), {static_cast<py::ssize_t>(d.input_vertex_count())});
          },
          "(input V,) int32 TDAG vertex standing for each input vertex (-1: used by no face)")
      .def_property_readonly(
          "affine_maps",
          [](const TemporalDag& d) {
            const size_t f = d.frame_count();
            std::vector<double> maps(f * 12);
            for (size_t t = 0; t < f; ++t) std::memcpy(&maps[t * 12], d.affine_map(static_cast<int32_t>(t)), 12 * sizeof(double));
            return numpy_from_vector(std::move(maps), {static_cast<py::ssize_t>(f), 3, 4});
          },
          "(F, 3, 4) float64 affine map of every frame (a copy)")
      .def(
          "residuals",
          [](const TemporalDag& d, int32_t frame) {
            check_frame(d, frame);
            std::vector<float> r(d.residuals(frame), d.residuals(frame) + d.vertex_count() * 3);
            return numpy_from_vector(std::move(r), {static_cast<py::ssize_t>(d.vertex_count()), 3});
          },
          py::arg("frame"), "(V, 3) float32 residual mesh of `frame` (a copy)")
      .def(
          "frame_positions",
          [](const TemporalDag& d, int32_t frame) {
            check_frame(d, frame);
            std::vector<float> p(d.vertex_count() * 3);
            d.frame_positions(frame, p.data());
            return numpy_from_vector(std::move(p), {static_cast<py::ssize_t>(d.vertex_count()), 3});
          },
          py::arg("frame"), "(V, 3) float32 input frame rebuilt from the affine map and the residuals")
      .def_property_readonly(
          "children",
          [](const TemporalDag& d) {
            std::vector<int32_t> c(d.collapse_count() * 2);
            for (size_t i = 0; i < d.collapse_count(); ++i) {
              c[2 * i] = d.kept_child(i);
              c[2 * i + 1] = d.removed_child(i);
            }
            return numpy_from_vector(std::move(c), {static_cast<py::ssize_t>(d.collapse_count()), 2});
          },
          "(C, 2) int32 (kept, removed) child node of every collapse; collapse c makes node V + c")
      .def_property_readonly(
          "representatives",
          [](const TemporalDag& d) {
            std::vector<int32_t> r(d.node_count());
            for (size_t n = 0; n < r.size(); ++n) r[n] = d.representative(static_cast<int32_t>(n));
            return numpy_from_vector(std::move(r), {static_cast<py::ssize_t>(r.size())});
          },
          "(V + C,) int32 input vertex whose position each node takes")
      .def(
          "alive",
          [](const TemporalDag& d, int64_t c) {
            check_collapse(d, c);
            std::vector<std::pair<int32_t, int32_t>> out;
            for (const FrameRange& r : d.alive(static_cast<size_t>(c)).ranges()) out.emplace_back(r.birth, r.death);
            return out;
          },
          py::arg("collapse"), "frame ranges [birth, death) on which the collapse is in the hierarchy")
      .def(
          "alive_mask",
          [](const TemporalDag& d, int32_t frame) {
            check_frame(d, frame);
            std::vector<uint8_t> mask(d.collapse_count());
            for (size_t c = 0; c < mask.size(); ++c) mask[c] = d.alive(c).alive_at(frame);
            return numpy_from_vector(std::move(mask), {static_cast<py::ssize_t>(d.collapse_count())}).attr("view")("bool");
          },
          py::arg("frame"), "(C,) bool: collapses in the hierarchy of `frame`")
      .def(
          "dependencies",
          [](const TemporalDag& d, int64_t c, int32_t frame) {
            check_collapse(d, c);
            check_frame(d, frame);
            return d.dependencies_at(static_cast<size_t>(c), frame);
          },
          py::arg("collapse"), py::arg("frame"), "collapse nodes the collapse needs at `frame`")
      .def(
          "parent",
          [](const TemporalDag& d, int32_t node, int32_t frame) {
            check_frame(d, frame);
            if (node < 0 || static_cast<size_t>(node) >= d.node_count()) throw py::value_error("node: out of range");
            return d.parent_at(node, frame);
          },
          py::arg("node"), py::arg("frame"), "the collapse node with `node` as a child at `frame`, or -1")
      .def(
          "error_bounds",
          [](const TemporalDag& d, int32_t frame) {
            check_frame(d, frame);
            std::vector<double> bounds(d.collapse_count());
            for (size_t c = 0; c < bounds.size(); ++c) bounds[c] = d.error_bound(c, frame);
            return numpy_from_vector(std::move(bounds), {static_cast<py::ssize_t>(d.collapse_count())});
          },
          py::arg("frame"), "(C,) float64 error bound of every collapse at `frame`, asset units (inf where not alive)")
      .def_property_readonly(
          "stored_counts",
          [](const TemporalDag& d) {
            size_t links = 0, ranges = 0;
            for (size_t c = 0; c < d.collapse_count(); ++c) {
              links += d.dependency_link_count(c);
              ranges += d.alive(c).ranges().size();
            }
            const size_t runs = d.error_run_count();
            py::dict out;
            out["dependency_links"] = links;
            out["error_runs"] = runs;
            out["alive_ranges"] = ranges;
            return out;
          },
          "counts of the stored tagged values: dependency links, error runs, alive ranges")
      .def(
          "to_bytes",
          [](const TemporalDag& d) {
            std::vector<uint8_t> bytes;
            call_released([&] { return serialize_temporal_dag(d, bytes); });
            const auto size = static_cast<py::ssize_t>(bytes.size());
            return numpy_from_vector(std::move(bytes), {size});
          },
          "the .tdag file contents (versioned, checksummed) as a (N,) uint8 array: no copy of a long "
          "clip's gigabytes")
      .def(
          "write",
          [](const TemporalDag& d, const py::object& handle) {
            // The core runs without the GIL and takes it for each piece it hands to the file; a
            // Python error (a full disk) stops the writing and is raised as it came.
            struct HandleSink : TdagFileSink {
              const py::object& handle;
              std::optional<py::error_already_set> error;
              explicit HandleSink(const py::object& h) : handle(h) {}
              bool call(const std::function<void()>& write) {
                py::gil_scoped_acquire acquire;
                try {
                  write();
                  return true;
                } catch (py::error_already_set& e) {
                  error = std::move(e);
                  return false;
                }
              }
              bool append(const uint8_t* bytes, size_t size) override {
                return call([&] { handle.attr("write")(py::memoryview::from_memory(bytes, static_cast<py::ssize_t>(size))); });
              }
              bool overwrite(size_t offset, const uint8_t* bytes, size_t size) override {
                return call([&] {
                  const py::object end = handle.attr("tell")();
                  handle.attr("seek")(offset);
                  handle.attr("write")(py::memoryview::from_memory(bytes, static_cast<py::ssize_t>(size)));
                  handle.attr("seek")(end);
                });
              }
            } sink(handle);
            Status status;
            {
              py::gil_scoped_release release;
              status = write_temporal_dag(d, sink);
            }
            if (sink.error) throw std::move(*sink.error);
            raise_if_error(status);
          },
          py::arg("handle"),
          "writes the .tdag file into a binary file object opened for writing and seeking, a piece at a time "
          "(never the whole file in memory); what its write raises is raised")
      .def_static(
          "from_bytes",
          [](const py::object& data) {  // any bytes-like object (an object, not py::buffer: the stub
                                          // would name typing_extensions.Buffer, not installed)
            if (!PyObject_CheckBuffer(data.ptr())) throw py::type_error("TemporalDag.from_bytes: expected bytes");
            const py::buffer_info info = py::reinterpret_borrow<py::buffer>(data).request();
            if (info.ndim != 1 || info.itemsize != 1 || info.strides[0] != 1)
              throw py::value_error("TemporalDag.from_bytes: expected contiguous bytes");
            TemporalDag dag;
            call_released([&] {
              return deserialize_temporal_dag(static_cast<const uint8_t*>(info.ptr), static_cast<size_t>(info.size), dag);
            });
            return dag;
          },
          py::arg("data"),
          "reads .tdag contents from any bytes-like object (bytes, a mapped file); ValueError for a non-TDAG, "
          "another version or a corrupted file")
      .def_static(
          "load",
          [](const std::string& path) {
            TemporalDag dag;
            call_released([&] { return load_temporal_dag(path, dag); });
            return dag;
          },
          py::arg("path"),
          "reads a .tdag file a chunk at a time (never the whole file in memory); ValueError starting with the "
          "path for a missing file, a non-TDAG, another version or a corrupted file");

  m.def("build_temporal_dag", &build_py, py::arg("frames"), py::arg("faces"), py::arg("options") = TdagOptions{},
        py::arg("progress") = py::none(),
        R"doc(Builds the TDAG of a deforming mesh (Shamir and Pascucci 2001, Sections 3-4).

frames (F, V, 3) float32, faces (M, 3) int32/int64 (manifold, consistently oriented); options a
TdagOptions; progress callable(done, total) over frames, called with the GIL held.
Returns (TemporalDag, report dict: collapse_counts (F,), max_cost (C,) and use_counts (C,) for
Figure 6, seconds_affine, seconds_hierarchy, seconds_fields). ValueError naming the element for
a bad mesh or option.)doc");

  m.def("affine_split", &affine_split_py, py::arg("frames"), py::arg("base") = "first",
        R"doc(Section 3: per frame the least-squares affine map from the base ('first' or 'average') to
the frame. Returns maps (F, 3, 4) float64, residuals (F, V, 3) float32 and translation_only (F,)
bool (frames whose map was singular and use their centroid's translation).)doc");

  py::class_<TdagCut>(m, "TdagCut", "A cut of a TDAG: a fresh or incrementally updated mesh (animlod/tdag.hpp).")
      .def(py::init<const TemporalDag&>(), py::arg("dag"))
      .def("copy", [](const TdagCut& c) { return TdagCut(c); })
      .def(
          "query",
          [](TdagCut& c, int32_t frame, double tolerance) { call_released([&] { return c.query(frame, tolerance); }); },
          py::arg("frame"), py::arg("tolerance"), "random query: the coarsest cut within `tolerance` (asset units)")
      .def(
          "query_view",
          [](TdagCut& c, int32_t frame, const std::vector<double>& camera, double pixels, double focal_pixels) {
            const ViewTolerance view = view_from(camera, pixels, focal_pixels);
            call_released([&] { return c.query_view(frame, view); });
          },
          py::arg("frame"), py::arg("camera"), py::arg("pixels") = 1.0, py::arg("focal_pixels") = 1000.0,
          "random query with a screen-space tolerance of `pixels` seen from `camera`")
      .def(
          "advance", [](TdagCut& c, int32_t frame) { call_released([&] { return c.advance(frame); }); },
          py::arg("frame"), "incremental in time: the cut for `frame`, same tolerance")
      .def(
          "refine", [](TdagCut& c, double tolerance) { call_released([&] { return c.refine(tolerance); }); },
          py::arg("tolerance"), "incremental in resolution: a new tolerance at the same frame")
      .def(
          "refine_view",
          [](TdagCut& c, const std::vector<double>& camera, double pixels, double focal_pixels) {
            const ViewTolerance view = view_from(camera, pixels, focal_pixels);
            call_released([&] { return c.refine_view(view); });
          },
          py::arg("camera"), py::arg("pixels") = 1.0, py::arg("focal_pixels") = 1000.0)
      .def(
          "approximate",
          [](TdagCut& c, int32_t frame, int level) {
            TdagMesh mesh;
            const ApproximationLevel l = level_from(level);
            call_released([&] { return c.approximate(frame, l, mesh); });
            return mesh_to_dict(std::move(mesh));
          },
          py::arg("frame"), py::arg("level") = 3,
          "Section 5 level 1 (affine), 2 (residual) or 3 (cut update) of `frame`: dict of positions (V', 3) "
          "float32, faces (M', 3) int32, nodes (V',), frame, cut_frame, residual_frame, error_bound")
      .def("mesh",
           [](const TdagCut& c) {
             TdagMesh mesh;
             c.mesh(mesh);
             return mesh_to_dict(std::move(mesh));
           })
      .def("input_vertex_map",
           [](const TdagCut& c) {
             std::vector<int32_t> map;
             c.input_vertex_map(map);
             const auto n = static_cast<py::ssize_t>(map.size());
             return numpy_from_vector(std::move(map), {n});
           })
      .def_property_readonly("frame", &TdagCut::frame)
      .def_property_readonly("tolerance", &TdagCut::tolerance)
      .def_property_readonly("has_query", &TdagCut::has_query)
      .def_property_readonly("active_vertex_count", &TdagCut::active_vertex_count)
      .def_property_readonly("active_face_count", &TdagCut::active_face_count)
      .def_property_readonly("error_bound", &TdagCut::error_bound)
      .def_property_readonly("last_split_count", &TdagCut::last_split_count)
      .def_property_readonly("last_collapse_count", &TdagCut::last_collapse_count);

  py::class_<TdagPlayer>(m, "TdagPlayer", "Double-buffered player (animlod/tdag_player.hpp).")
      .def(py::init<const TemporalDag&>(), py::arg("dag"))
      .def(
          "start",
          [](TdagPlayer& p, double tolerance, int32_t first_frame) {
            call_released([&] { return p.start(tolerance, first_frame); });
          },
          py::arg("tolerance"), py::arg("first_frame") = 0)
      .def(
          "next",
          [](TdagPlayer& p, int level) {
            TdagMesh mesh;
            const ApproximationLevel l = level_from(level);
            call_released([&] { return p.next(l, mesh); });
            return mesh_to_dict(std::move(mesh));
          },
          py::arg("level") = 3)
      .def("next_available",
           [](TdagPlayer& p) {
             TdagMesh mesh;
             ApproximationLevel used = ApproximationLevel::full;
             call_released([&] { return p.next_available(mesh, used); });
             return py::make_tuple(mesh_to_dict(std::move(mesh)), static_cast<int>(used));
           })
      .def_property_readonly("frame", &TdagPlayer::frame)
      .def_property_readonly("done", &TdagPlayer::done);

  m.def(
      "play_temporal_dag",
      [](const TemporalDag& dag, const PlayerOptions& options) {
        PlayerReport report;
        call_released([&] { return play_temporal_dag(dag, options, report); });
        py::dict out;
        out["frames"] = report.frames;
        py::list levels;
        for (const auto& stats : report.levels) levels.append(stats_to_dict(stats));
        out["levels"] = levels;
        out["full_query"] = stats_to_dict(report.full_query);
        out["mean_splits"] = report.mean_splits;
        out["mean_collapses"] = report.mean_collapses;
        out["sequential_seconds_per_frame"] = report.sequential_seconds_per_frame;
        out["double_buffered_seconds_per_frame"] = report.double_buffered_seconds_per_frame;
        out["median_update_seconds"] = report.median_update_seconds;
        out["median_fresh_cut_seconds"] = report.median_fresh_cut_seconds;
        return out;
      },
      py::arg("dag"), py::arg("options") = PlayerOptions{},
      "Walks the frames and measures levels 1-3, a fresh query, and the level-3 walk single- and "
      "double-buffered (animlod/tdag_player.hpp, PlayerReport) as a dict.");
}

}  // namespace animlod::bindings
