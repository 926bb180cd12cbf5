#include "fralab/exchange/mat_file.h"

#include <matio.h>

#include <cctype>
#include <deque>

#include "fralab/core/error.h"

namespace fralab {

MatValue MatValue::scalar(double v) { return matrix(1, 1, {v}); }

MatValue MatValue::column(const std::vector<double>& v) { return matrix(v.size(), 1, v); }

MatValue MatValue::structure() {
  MatValue m;
  m.kind = Kind::kStruct;
  return m;
}

MatValue MatValue::matrix(size_t rows, size_t cols, std::vector<double> v) {
  MatValue m;
  m.kind = Kind::kReal;
  m.rows = rows;
  m.cols = cols;
  m.real = std::move(v);
  return m;
}

MatValue MatValue::complex_column(const std::vector<std::complex<double>>& v) {
  MatValue m;
  m.kind = Kind::kComplex;
  m.rows = v.size();
  m.cols = 1;
  m.complex = v;
  return m;
}

MatValue MatValue::str(const std::string& s) {
  MatValue m;
  m.kind = Kind::kText;
  m.text = s;
  return m;
}

MatValue MatValue::str_list(const std::vector<std::string>& s) {
  MatValue m;
  m.kind = Kind::kTextList;
  m.texts = s;
  return m;
}

MatValue& MatValue::add(const std::string& name, MatValue v) {
  field_names.push_back(name);
  field_values.push_back(std::move(v));
  return field_values.back();
}

bool is_mat_name(const std::string& name) {
  if (name.empty() || name.size() > 63 || !std::isalpha(static_cast<unsigned char>(name[0])))
    return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

namespace {

// matio variables are built bottom-up; a struct or cell owns (and frees) the variables set into
// it. Data are not copied (MAT_F_DONT_COPY_DATA): they stay in `v` or in `keep`, which outlive the
// variable (matio's copy of a complex split is not to be relied on).
struct Keep {
  std::deque<std::vector<double>> arrays;
  std::deque<mat_complex_split_t> splits;
};

struct MatCloser {
  void operator()(mat_t* m) const { Mat_Close(m); }
};
struct VarFreer {
  void operator()(matvar_t* v) const { Mat_VarFree(v); }
};

// A char row (0 x 0 when empty), its data left in `text`.
matvar_t* char_var(const char* name, const std::string& text) {
  size_t dims[2] = {text.empty() ? size_t(0) : size_t(1), text.size()};
  return Mat_VarCreate(name, MAT_C_CHAR, MAT_T_UTF8, 2, dims,
                       text.empty() ? nullptr : const_cast<char*>(text.data()),
                       MAT_F_DONT_COPY_DATA);
}

matvar_t* make_var(const std::string& name, const MatValue& v, const std::string& where,
                   Keep* keep) {
  const char* n = name.empty() ? nullptr : name.c_str();
  matvar_t* var = nullptr;
  switch (v.kind) {
    case MatValue::Kind::kReal: {
      if (v.real.size() != v.rows * v.cols)
        throw InputError(where + ": " + std::to_string(v.real.size()) + " values for a " +
                         std::to_string(v.rows) + "x" + std::to_string(v.cols) + " matrix");
      size_t dims[2] = {v.rows, v.cols};
      var = Mat_VarCreate(n, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims,
                          const_cast<double*>(v.real.data()), MAT_F_DONT_COPY_DATA);
      break;
    }
    case MatValue::Kind::kComplex: {
      std::vector<double>& re = keep->arrays.emplace_back();
      std::vector<double>& im = keep->arrays.emplace_back();
      for (const auto& z : v.complex) {
        re.push_back(z.real());
        im.push_back(z.imag());
      }
      mat_complex_split_t& split =
          keep->splits.emplace_back(mat_complex_split_t{re.data(), im.data()});
      size_t dims[2] = {v.complex.size(), 1};
      var = Mat_VarCreate(n, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, &split,
                          MAT_F_COMPLEX | MAT_F_DONT_COPY_DATA);
      break;
    }
    case MatValue::Kind::kText:
      var = char_var(n, v.text);
      break;
    case MatValue::Kind::kTextList: {
      size_t dims[2] = {1, v.texts.size()};
      var = Mat_VarCreate(n, MAT_C_CELL, MAT_T_CELL, 2, dims, nullptr, 0);
      for (size_t i = 0; var && i < v.texts.size(); ++i)
        Mat_VarSetCell(var, int(i), char_var(nullptr, v.texts[i]));
      break;
    }
    case MatValue::Kind::kStruct: {
      std::vector<const char*> names;
      for (const std::string& f : v.field_names) {
        if (!is_mat_name(f)) throw InputError(where + ": '" + f + "' is not a MATLAB field name");
        names.push_back(f.c_str());
      }
      size_t dims[2] = {1, 1};
      names.push_back(nullptr);  // the list ends with a null
      // Held while its fields are made: a field that fails frees the struct too.
      std::unique_ptr<matvar_t, VarFreer> st(Mat_VarCreateStruct2(n, 2, dims, names.data()));
      for (size_t k = 0; st && k < v.field_names.size(); ++k) {
        const std::string& f = v.field_names[k];
        Mat_VarSetStructFieldByName(st.get(), f.c_str(), 0,
                                    make_var(f, v.field_values[k], where + "." + f, keep));
      }
      var = st.release();
      break;
    }
  }
  if (!var) throw InputError(where + ": matio could not create the variable");
  return var;
}

}  // namespace

void write_mat_file(const std::string& path,
                    const std::vector<std::pair<std::string, MatValue>>& variables) {
  std::unique_ptr<mat_t, MatCloser> mat(Mat_CreateVer(path.c_str(), nullptr, MAT_FT_MAT5));
  if (!mat) throw InputError(path + ": cannot be created");
  for (const auto& [name, value] : variables) {
    if (!is_mat_name(name)) throw InputError(path + ": '" + name + "' is not a MATLAB name");
    Keep keep;
    std::unique_ptr<matvar_t, VarFreer> var(make_var(name, value, path + ": " + name, &keep));
    if (Mat_VarWrite(mat.get(), var.get(), MAT_COMPRESSION_ZLIB) != 0)
      throw InputError(path + ": writing " + name + " failed");
  }
}

namespace {
template <class T>
std::vector<double> as_doubles(const void* data, size_t n) {
  const T* p = static_cast<const T*>(data);
  return std::vector<double>(p, p + n);
}
}  // namespace

std::vector<std::pair<std::string, std::vector<double>>> read_mat_vectors(
    const std::string& path, std::vector<std::string>* skipped) {
  std::unique_ptr<mat_t, MatCloser> mat(Mat_Open(path.c_str(), MAT_ACC_RDONLY));
  if (!mat) throw InputError(path + ": not a .mat file matio can read");
  std::vector<std::pair<std::string, std::vector<double>>> out;
  while (true) {
    std::unique_ptr<matvar_t, VarFreer> v(Mat_VarReadNext(mat.get()));
    if (!v) break;
    const std::string name = v->name ? v->name : "";
    const bool vector = v->rank == 2 && (v->dims[0] == 1 || v->dims[1] == 1);
    const size_t n = vector ? v->dims[0] * v->dims[1] : 0;
    std::vector<double> d;
    bool ok = vector && !v->isComplex && !v->isLogical && v->data != nullptr;
    if (ok) {
      switch (v->class_type) {
        case MAT_C_DOUBLE:
          d = as_doubles<double>(v->data, n);
          break;
        case MAT_C_SINGLE:
          d = as_doubles<float>(v->data, n);
          break;
        case MAT_C_INT8:
          d = as_doubles<int8_t>(v->data, n);
          break;
        case MAT_C_UINT8:
          d = as_doubles<uint8_t>(v->data, n);
          break;
        case MAT_C_INT16:
          d = as_doubles<int16_t>(v->data, n);
          break;
        case MAT_C_UINT16:
          d = as_doubles<uint16_t>(v->data, n);
          break;
        case MAT_C_INT32:
          d = as_doubles<int32_t>(v->data, n);
          break;
        case MAT_C_UINT32:
          d = as_doubles<uint32_t>(v->data, n);
          break;
        case MAT_C_INT64:
          d = as_doubles<int64_t>(v->data, n);
          break;
        case MAT_C_UINT64:
          d = as_doubles<uint64_t>(v->data, n);
          break;
        default:
          ok = false;
      }
    }
    if (ok)
      out.emplace_back(name, std::move(d));
    else if (skipped)
      skipped->push_back(name);
  }
  return out;
}

}  // namespace fralab
