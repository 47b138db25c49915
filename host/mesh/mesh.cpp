#include "vpm/mesh.hpp"

#include <stdexcept>

#include "vpm/error.hpp"

namespace vpm {

namespace {
const Field* find(const std::vector<Field>& fields, const std::string& name) {
  for (const auto& f : fields)
    if (f.name == name) return &f;
  return nullptr;
}
void set(std::vector<Field>& fields, const std::string& name, FieldValues values, bool integer,
         Eigen::Index rows, const char* what) {
  if (values.rows() != rows)
    throw std::invalid_argument(std::string(what) + " field '" + name + "' has " +
                                std::to_string(values.rows()) + " rows, expected " +
                                std::to_string(rows));
  for (auto& f : fields)
    if (f.name == name) {
      f.values = std::move(values);
      f.integer = integer;
      return;
    }
  fields.push_back(Field{name, std::move(values), integer});
}
}  // namespace

const Field* TetMesh::find_point_field(const std::string& name) const { return find(point_data, name); }
const Field* TetMesh::find_cell_field(const std::string& name) const { return find(cell_data, name); }
void TetMesh::set_point_field(const std::string& name, FieldValues values, bool integer) {
  set(point_data, name, std::move(values), integer, vertices.rows(), "point");
}
void TetMesh::set_cell_field(const std::string& name, FieldValues values, bool integer) {
  set(cell_data, name, std::move(values), integer, tets.rows(), "cell");
}

Points native_positions(const TetMesh& mapped, const std::string& what) {
  const Field* f = mapped.find_point_field("original_position");
  if (!f || f->values.cols() != 3)
    throw InputError(what + ": no point field original_position (3 components): not a mesh mapped by `vpm map`");
  return f->values;
}

}  // namespace vpm
