#include "fralab/exchange/state_space_mat.h"

#include <matio.h>

#include <filesystem>
#include <functional>
#include <memory>

#include "fralab/core/error.h"
#include "fralab/exchange/mat_file.h"

namespace fralab {
namespace {

struct StateMatCloser {
  void operator()(mat_t* m) const { Mat_Close(m); }
};
struct StateVarFreer {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};
using StateVarPtr = std::unique_ptr<matvar_t, StateVarFreer>;

// A real numeric matrix (double or single), column-major.
Eigen::MatrixXd real_matrix(const matvar_t* v, const std::string& where) {
  if (!v || v->rank != 2 || v->isComplex || !v->data ||
      (v->class_type != MAT_C_DOUBLE && v->class_type != MAT_C_SINGLE))
    throw InputError(where + ": not a real matrix of numbers");
  const Eigen::Index r = Eigen::Index(v->dims[0]), c = Eigen::Index(v->dims[1]);
  Eigen::MatrixXd m(r, c);
  for (Eigen::Index k = 0; k < r * c; ++k)
    m(k % r, k / r) = v->class_type == MAT_C_DOUBLE ? static_cast<const double*>(v->data)[k]
                                                    : static_cast<const float*>(v->data)[k];
  return m;
}

// The text of a char array's row `row` (trailing blanks and NULs dropped).
std::string char_row(const matvar_t* v, size_t row, const std::string& where) {
  if (!v || v->class_type != MAT_C_CHAR || v->rank != 2 || !v->data)
    throw InputError(where + ": not text");
  const size_t rows = v->dims[0], cols = v->dims[1];
  std::string s;
  for (size_t q = 0; q < cols; ++q) {
    const size_t k = row + q * rows;
    unsigned code = 0;
    if (v->data_type == MAT_T_UINT16 || v->data_type == MAT_T_UTF16)
      code = static_cast<const uint16_t*>(v->data)[k];
    else
      code = static_cast<const uint8_t*>(v->data)[k];
    s += char(code < 128 ? code : '?');
  }
  while (!s.empty() && (s.back() == ' ' || s.back() == '\0')) s.pop_back();
  return s;
}

// A cell array of text (or a char matrix, one name a row) as names.
std::vector<std::string> names(const matvar_t* v, const std::string& where) {
  std::vector<std::string> out;
  if (v && v->class_type == MAT_C_CELL) {
    const size_t n = v->dims[0] * v->dims[1];
    for (size_t k = 0; k < n; ++k)
      out.push_back(char_row(Mat_VarGetCell(const_cast<matvar_t*>(v), int(k)), 0,
                             where + "{" + std::to_string(k + 1) + "}"));
    return out;
  }
  if (v && v->class_type == MAT_C_CHAR) {
    for (size_t r = 0; r < v->dims[0]; ++r) out.push_back(char_row(v, r, where));
    return out;
  }
  throw InputError(where + ": not a cell array of names");
}

std::vector<double> vector_of(const matvar_t* v, const std::string& where) {
  const Eigen::MatrixXd m = real_matrix(v, where);
  return std::vector<double>(m.data(), m.data() + m.size());
}

std::vector<std::string> default_names(const std::string& prefix, Eigen::Index n) {
  std::vector<std::string> out;
  for (Eigen::Index k = 0; k < n; ++k) out.push_back(prefix + std::to_string(k + 1));
  return out;
}

// A state model from named values (variables of the file or fields of one struct).
StateSpace from_fields(const std::function<const matvar_t*(const char*)>& get,
                       const std::string& where) {
  StateSpace ss;
  for (const char* key : {"A", "B", "C"})
    if (!get(key))
      throw InputError(where + ": no variable " + key + " (nor ABCD and nx, Dymola's)");
  ss.A = real_matrix(get("A"), where + ": A");
  ss.B = real_matrix(get("B"), where + ": B");
  ss.C = real_matrix(get("C"), where + ": C");
  ss.D = get("D") ? real_matrix(get("D"), where + ": D")
                  : Eigen::MatrixXd::Zero(ss.C.rows(), ss.B.cols());
  ss.states = get("StateName") ? names(get("StateName"), where + ": StateName")
                               : default_names("x", ss.A.rows());
  // InputName/OutputName as MATLAB names them; inputs/outputs as `fralab export` writes them.
  const char* in_key = get("InputName") ? "InputName" : get("inputs") ? "inputs" : nullptr;
  const char* out_key = get("OutputName") ? "OutputName" : get("outputs") ? "outputs" : nullptr;
  ss.inputs = in_key ? names(get(in_key), where + ": " + in_key) : default_names("u", ss.B.cols());
  ss.outputs =
      out_key ? names(get(out_key), where + ": " + out_key) : default_names("y", ss.C.rows());
  if (get("delay_s")) ss.path_delay_s = real_matrix(get("delay_s"), where + ": delay_s");
  if (get("InputDelay")) ss.input_delay_s = vector_of(get("InputDelay"), where + ": InputDelay");
  if (get("OutputDelay"))
    ss.output_delay_s = vector_of(get("OutputDelay"), where + ": OutputDelay");
  // MATLAB saves an unnamed channel as '' : those take the default names.
  for (auto [list, prefix] : {std::pair{&ss.states, "x"}, {&ss.inputs, "u"}, {&ss.outputs, "y"}})
    for (size_t k = 0; k < list->size(); ++k)
      if ((*list)[k].empty()) (*list)[k] = prefix + std::to_string(k + 1);
  return ss;
}

}  // namespace

StateSpace read_state_space_mat(const std::string& path) {
  std::unique_ptr<mat_t, StateMatCloser> mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!mat)
    throw InputError(path +
                     ": not a .mat file matio can read (a v7.3 file needs matio's HDF5 support)");
  std::vector<StateVarPtr> vars;
  while (matvar_t* v = Mat_VarReadNext(mat.get())) vars.emplace_back(v);
  auto var = [&](const char* name) -> const matvar_t* {
    for (const auto& v : vars)
      if (v->name && std::string(v->name) == name) return v.get();
    return nullptr;
  };
  // Dymola: ABCD, nx, xuyName.
  if (var("ABCD")) {
    const Eigen::MatrixXd abcd = real_matrix(var("ABCD"), path + ": ABCD");
    if (!var("nx")) throw InputError(path + ": ABCD without nx (Dymola's number of states)");
    const Eigen::MatrixXd nxm = real_matrix(var("nx"), path + ": nx");
    const double nxd = nxm.size() == 1 ? nxm(0, 0) : -1;
    if (!(nxd >= 1) || nxd != std::floor(nxd) || nxd > double(std::min(abcd.rows(), abcd.cols())))
      throw InputError(path + ": nx is not a number of states between 1 and the size of ABCD");
    const Eigen::Index nx = Eigen::Index(nxd), nu = abcd.cols() - nx, ny = abcd.rows() - nx;
    StateSpace ss;
    ss.A = abcd.topLeftCorner(nx, nx);
    ss.B = abcd.topRightCorner(nx, nu);
    ss.C = abcd.bottomLeftCorner(ny, nx);
    ss.D = abcd.bottomRightCorner(ny, nu);
    std::vector<std::string> all =
        var("xuyName") ? names(var("xuyName"), path + ": xuyName") : std::vector<std::string>{};
    if (!all.empty() && Eigen::Index(all.size()) != nx + nu + ny)
      throw InputError(path + ": xuyName has " + std::to_string(all.size()) + " names for " +
                       std::to_string(nx + nu + ny) + " states, inputs and outputs (ABCD)");
    auto part = [&](Eigen::Index from, Eigen::Index n, const std::string& prefix) {
      return all.empty() ? default_names(prefix, n)
                         : std::vector<std::string>(all.begin() + from, all.begin() + from + n);
    };
    ss.states = part(0, nx, "x");
    ss.inputs = part(nx, nu, "u");
    ss.outputs = part(nx + nu, ny, "y");
    return ss;
  }
  if (var("A")) return from_fields(var, path);
  // One struct holding the fields.
  for (const auto& v : vars)
    if (v->class_type == MAT_C_STRUCT && Mat_VarGetStructFieldByName(v.get(), "A", 0)) {
      const std::string where = path + ": " + (v->name ? v->name : "?");
      return from_fields(
          [&](const char* f) -> const matvar_t* {
            return Mat_VarGetStructFieldByName(v.get(), f, 0);
          },
          where);
    }
  throw InputError(path +
                   ": no state model (variables A, B, C, a struct holding them, or "
                   "Dymola's ABCD and nx)");
}

std::optional<Json> state_space_document_if_mat(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext != ".mat") return std::nullopt;
  const StateSpace ss = read_state_space_mat(path);
  Json doc = state_space_document(ss, std::filesystem::path(path).stem().string());
  std::unique_ptr<mat_t, StateMatCloser> mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  StateVarPtr rest(mat ? Mat_VarRead(mat.get(), "fralab_ss") : nullptr);
  if (!rest) return doc;
  const std::string where = path + ": fralab_ss";
  Json given;
  try {
    given = Json::parse(char_row(rest.get(), 0, where));
  } catch (const Json::exception& e) {
    throw InputError(where + ": not JSON text (" + e.what() + ")");
  }
  if (!given.is_object()) throw InputError(where + ": not a fralab-ss/1 document's keys");
  // The channels as the document gives them, in the matrices' order, with the matrices' delays.
  for (const char* key : {"inputs", "outputs"}) {
    const Json& have = doc[key];
    if (!given.contains(key) || !given[key].is_array() || given[key].size() != have.size())
      throw InputError(where + ": its " + key + " are not the matrices' " +
                       std::to_string(have.size()));
    for (size_t k = 0; k < have.size(); ++k) {
      Json ch = given[key][k];
      if (!ch.is_object() || ch.value("name", "") != have[k]["name"])
        throw InputError(where + ": " + key + "[" + std::to_string(k) + "] is not " +
                         have[k]["name"].get<std::string>());
      ch.erase("delay_s");
      if (have[k].contains("delay_s")) ch["delay_s"] = have[k]["delay_s"];
      given[key][k] = ch;
    }
  }
  for (const char* key : {"format", "states", "A", "B", "C", "D", "delay_s"}) {
    given.erase(key);
    if (doc.contains(key)) given[key] = doc[key];
  }
  return given;
}

void write_state_space_mat(const std::string& path, const Json& doc) {
  const StateSpace ss = state_space_from_json(doc, path);
  ss.validate(path);
  auto mat = [](const Eigen::MatrixXd& x) {
    return MatValue::matrix(size_t(x.rows()), size_t(x.cols()),
                            std::vector<double>(x.data(), x.data() + x.size()));
  };
  std::vector<std::pair<std::string, MatValue>> vars = {
      {"A", mat(ss.A)},
      {"B", mat(ss.B)},
      {"C", mat(ss.C)},
      {"D", mat(ss.D)},
      {"StateName", MatValue::str_list(ss.states)},
      {"InputName", MatValue::str_list(ss.inputs)},
      {"OutputName", MatValue::str_list(ss.outputs)},
      {"InputDelay", MatValue::column(ss.input_delay_s)},
      {"OutputDelay", MatValue::column(ss.output_delay_s)},
      {"delay_s", mat(ss.path_delay_s.size() ? ss.path_delay_s
                                             : Eigen::MatrixXd::Zero(ss.C.rows(), ss.B.cols()))}};
  MatValue actuators = MatValue::structure();
  for (size_t k = 0; k < ss.inputs.size(); ++k) {
    const Json& in = doc["inputs"][k];
    if (!in.contains("actuator") || !is_mat_name(ss.inputs[k])) continue;
    const Tf t = tf_from_json(in["actuator"]["tf"], {path, "/inputs/" + std::to_string(k)});
    MatValue a = MatValue::structure();
    const std::vector<double> num = t.numerator_coefficients(), den = t.denominator_coefficients();
    a.add("num", MatValue::matrix(1, num.size(), num));
    a.add("den", MatValue::matrix(1, den.size(), den));
    a.add("delay_s", MatValue::scalar(t.delay_s));
    actuators.add(ss.inputs[k], a);
  }
  if (!actuators.field_names.empty()) vars.emplace_back("actuators", actuators);
  Json rest = doc;
  for (const char* key : {"A", "B", "C", "D", "states"}) rest.erase(key);
  vars.emplace_back("fralab_ss", MatValue::str(rest.dump(-1, ' ', true)));
  write_mat_file(path, vars);
}

}  // namespace fralab
