// vpm.Image (a 3-D image with its voxel -> world affine), read_image (NIfTI, MGH/MGZ),
// write_nifti, and mesh_image.
#include "common.hpp"
#include "report.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/mesh_image.hpp"

namespace vpm::python {
namespace {

std::shared_ptr<Image> image_from_array(const py::handle& data, const py::handle& affine) {
  const auto a = py::array_t<float, py::array::f_style | py::array::forcecast>::ensure(data);
  if (!a || a.ndim() != 3) throw InputError("image: expected a 3-D array (i, j, k)");
  const auto t = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(affine);
  if (!t || t.ndim() != 2 || t.shape(0) != 4 || t.shape(1) != 4) throw InputError("affine: expected a 4 x 4 array");
  auto img = std::make_shared<Image>();
  img->dims = {static_cast<int>(a.shape(0)), static_cast<int>(a.shape(1)), static_cast<int>(a.shape(2))};
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) img->affine(r, c) = t.at(r, c);
  if (!(std::abs(img->affine.topLeftCorner<3, 3>().determinant()) > 0)) throw InputError("affine: singular");
  for (int j = 0; j < 3; ++j) img->spacing[j] = img->affine.block<3, 1>(0, j).norm();
  img->affine_source = "array";
  img->data.assign(a.data(), a.data() + a.size());  // Fortran order: i fastest, as Image stores it
  return img;
}

// long: the keyword arguments of `vpm mesh-image`, one line each
py::tuple mesh_image_py(const py::object& image, const py::object& labels, double threshold,
                        std::vector<int> select_labels, int target_vertices, double max_volume, double smooth,
                        bool close_at_border, double radius_edge, double min_dihedral, py::object progress) {
  MeshImageOptions o;
  o.threshold = threshold;
  o.select_labels = std::move(select_labels);
  o.target_vertices = target_vertices;
  o.max_volume = max_volume;
  o.smooth = smooth;
  o.close_at_border = close_at_border;
  o.radius_edge = radius_edge;
  o.min_dihedral_deg = min_dihedral;
  Progress p(std::move(progress));
  o.progress = p.function();
  MeshImageReport report;
  std::shared_ptr<TetMesh> mesh;
  if (py::isinstance<py::str>(image)) {
    const std::string path = image.cast<std::string>(), lpath = labels.is_none() ? "" : labels.cast<std::string>();
    mesh = without_gil(&p, [&] { return std::make_shared<TetMesh>(mesh_image_file(path, o, &report, lpath)); });
  } else {
    auto img = image.cast<std::shared_ptr<Image>>();
    auto atlas = labels.is_none() ? nullptr : labels.cast<std::shared_ptr<Image>>();
    mesh = without_gil(&p, [&] { return std::make_shared<TetMesh>(mesh_image(*img, o, &report, atlas.get())); });
  }
  return py::make_tuple(mesh, json_to_python(to_json(report)));
}

}  // namespace

void bind_image(py::module_& m) {
  py::class_<Image, std::shared_ptr<Image>>(m, "Image", R"(A 3-D scalar image and its voxel -> world (mm) affine.

Image(data, affine) copies a 3-D array (indexed i, j, k as nibabel gives it) as float32.
`data` is an (i, j, k) float32 view of the image's own memory (Fortran order, no copy).)")
      .def(py::init(&image_from_array), py::arg("data"), py::arg("affine"))
      .def_property_readonly(
          "data",
          [](const py::object& self) {
            auto& img = self.cast<Image&>();
            const py::ssize_t f = sizeof(float);
            return py::array_t<float>({img.dims[0], img.dims[1], img.dims[2]},
                                      {f, f * img.dims[0], f * img.dims[0] * img.dims[1]}, img.data.data(), self);
          })
      .def_property_readonly("affine",
                             [](const Image& img) {
                               Eigen::Matrix<double, 4, 4, Eigen::RowMajor> a = img.affine;
                               return py::array_t<double>({4, 4}, a.data());
                             })
      .def_property_readonly("shape", [](const Image& img) { return py::make_tuple(img.dims[0], img.dims[1], img.dims[2]); })
      .def_property_readonly("spacing", [](const Image& img) { return img.spacing; })
      .def_readonly("affine_source", &Image::affine_source, "'sform', 'qform', 'pixdim', 'mgh' or 'array'")
      .def_readonly("path", &Image::path)
      .def("__repr__", [](const Image& img) {
        return "<vpm.Image " + std::to_string(img.dims[0]) + "x" + std::to_string(img.dims[1]) + "x" +
               std::to_string(img.dims[2]) + ", affine from " + img.affine_source + ">";
      });
  m.def(
      "read_image",
      [](const std::string& path) {
        py::gil_scoped_release release;
        return std::make_shared<Image>(read_image(path));
      },
      py::arg("path"),
      "Reads a NIfTI-1/2 (.nii, .nii.gz) or FreeSurfer MGH (.mgh, .mgz) volume; world mm from the\n"
      "sform/qform or the MGH header (vox2ras, as nibabel's). ValueError naming the file otherwise.");
  m.def(
      "write_nifti",
      [](const std::string& path, const Image& img) {
        py::gil_scoped_release release;
        write_nifti(path, img);
      },
      py::arg("path"), py::arg("image"), "Writes a NIfTI-1 image (float32, sform and qform from the affine).");
  m.def("_mesh_image", &mesh_image_py, py::arg("image"), py::arg("labels") = py::none(), py::kw_only(),
        py::arg("threshold") = 0.0, py::arg("select_labels") = std::vector<int>{},
        py::arg("target_vertices") = MeshImageOptions{}.target_vertices, py::arg("max_volume") = 0.0,
        py::arg("smooth") = -1.0, py::arg("close_at_border") = false,
        py::arg("radius_edge") = MeshImageOptions{}.radius_edge,
        py::arg("min_dihedral") = MeshImageOptions{}.min_dihedral_deg, py::arg("progress") = py::none());
}

}  // namespace vpm::python
