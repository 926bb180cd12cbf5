// State models from .mat files (exchange/state_space_mat.h): Octave's v5 files (variables, a
// struct) and Dymola's dslin.mat layout (level 4), written by tests/data/state_space/make_mat.m,
// and a v7.3 (HDF5) file written here through matio: each read to the same matrices and names as
// tests/data/state_space/ss.json, bit for bit; bad files refused naming the file and variable.
#include "fralab/exchange/state_space_mat.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <matio.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "fralab/core/error.h"
#include "fralab/exchange/mat_file.h"
#include "fralab/plant/realisation.h"
#include "test_util.h"

namespace fralab {
namespace {

using ::testing::HasSubstr;
using testing::source_path;

StateSpace reference() {
  return state_space_from_json(json_load_file(source_path("tests/data/state_space/ss.json")),
                               "ss.json");
}

void expect_same(const StateSpace& got, const StateSpace& want, bool names, bool delays) {
  EXPECT_EQ(got.A, want.A);  // bit for bit
  EXPECT_EQ(got.B, want.B);
  EXPECT_EQ(got.C, want.C);
  EXPECT_EQ(got.D, want.D);
  if (names) {
    EXPECT_EQ(got.states, want.states);
    EXPECT_EQ(got.inputs, want.inputs);
    EXPECT_EQ(got.outputs, want.outputs);
  }
  if (delays) {
    EXPECT_EQ(got.input_delay_s, want.input_delay_s);
    EXPECT_EQ(got.output_delay_s, want.output_delay_s);
  }
}

TEST(StateSpaceMat, OctavesVariablesAndStructAndDymolasDslinReadToTheSameModel) {
  const StateSpace want = reference();
  const std::string dir = source_path("tests/data/state_space/");
  expect_same(read_state_space_mat(dir + "ss_variables_v7.mat"), want, true, true);
  expect_same(read_state_space_mat(dir + "ss_struct_v6.mat"), want, true, true);
  expect_same(read_state_space_mat(dir + "dslin.mat"), want, true, false);
}

// A v7.3 file (HDF5), as MATLAB's `save -v7.3` writes: A, B, C, D as doubles.
TEST(StateSpaceMat, AVersion73FileReadsToTheSameMatrices) {
  const StateSpace want = reference();
  const std::string file = ::testing::TempDir() + "/ss_v73.mat";
  mat_t* mat = Mat_CreateVer(file.c_str(), nullptr, MAT_FT_MAT73);
  ASSERT_NE(mat, nullptr) << "matio without HDF5 support";
  for (auto [name, m] : {std::pair<const char*, const Eigen::MatrixXd*>{"A", &want.A},
                         {"B", &want.B},
                         {"C", &want.C},
                         {"D", &want.D}}) {
    size_t dims[2] = {size_t(m->rows()), size_t(m->cols())};
    Eigen::MatrixXd copy = *m;  // column-major, as matio takes it
    matvar_t* v = Mat_VarCreate(name, MAT_C_DOUBLE, MAT_T_DOUBLE, 2, dims, copy.data(), 0);
    ASSERT_EQ(Mat_VarWrite(mat, v, MAT_COMPRESSION_NONE), 0);
    Mat_VarFree(v);
  }
  Mat_Close(mat);
  const StateSpace got = read_state_space_mat(file);
  expect_same(got, want, false, false);
  EXPECT_EQ(got.inputs, (std::vector<std::string>{"u1", "u2"}));  // unnamed: the defaults
  std::filesystem::remove(file);
}

// The identified state model as `fralab export` writes it (a struct `ss`: A, B, C, D, a delay per
// path, inputs and outputs by name) reads back with its per-path delays.
TEST(StateSpaceMat, TheStateModelFralabExportsReadsBackWithItsPathDelays) {
  const StateSpace want = reference();
  auto mat = [](const Eigen::MatrixXd& m) {
    return MatValue::matrix(size_t(m.rows()), size_t(m.cols()),
                            std::vector<double>(m.data(), m.data() + m.size()));
  };
  Eigen::MatrixXd delays(3, 2);
  delays << 0.01, 0, 0.012, 0.002, 0.01, 0;
  MatValue ss = MatValue::structure();
  ss.add("A", mat(want.A));
  ss.add("B", mat(want.B));
  ss.add("C", mat(want.C));
  ss.add("D", mat(want.D));
  ss.add("delay_s", mat(delays));
  ss.add("inputs", MatValue::str_list(want.inputs));
  ss.add("outputs", MatValue::str_list(want.outputs));
  const std::string file = ::testing::TempDir() + "/exported.mat";
  write_mat_file(file, {{"ss", ss}});
  const StateSpace got = read_state_space_mat(file);
  expect_same(got, want, false, false);
  EXPECT_EQ(got.inputs, want.inputs);
  EXPECT_EQ(got.outputs, want.outputs);
  EXPECT_EQ(got.path_delay_s, delays);
  EXPECT_EQ(got.states, (std::vector<std::string>{"x1", "x2", "x3", "x4"}));
  const Model m = parse_model(state_space_document(got, "exported"), file);
  EXPECT_DOUBLE_EQ(m.path("temp", "fuel")->tf.delay_s, 0.012);
  std::filesystem::remove(file);
}

// The model read from .mat and from its JSON give the same responses.
TEST(StateSpaceMat, TheModelFromMatRespondsAsTheModelFromJson) {
  const Json doc =
      *state_space_document_if_mat(source_path("tests/data/state_space/ss_variables_v7.mat"));
  const Model from_mat = parse_model(doc, "ss_variables_v7.mat");
  const Model from_json =
      parse_model(json_load_file(source_path("tests/data/state_space/ss.json")), "ss.json");
  ASSERT_EQ(from_mat.paths.size(), from_json.paths.size());
  for (size_t k = 0; k < from_json.paths.size(); ++k)
    for (double w = 1e-2; w < 1e3; w *= 2)
      EXPECT_LT(std::abs(from_mat.paths[k].tf.at(w) - from_json.paths[k].tf.at(w)),
                1e-9 * std::abs(from_json.paths[k].tf.at(w)));
}

// The J85 simulation as a state model (plant/realisation.h) written by fralab: its matrices,
// names and delays read back bit for bit, and the channels (units, actuators) with them.
TEST(StateSpaceMat, AModelWrittenAsAStateModelReadsBackBitForBitWithItsActuators) {
  const Model m = load_model(source_path("models/j85_95_sim.json"));
  const StateSpace want = model_state_space(m);
  const std::string file = ::testing::TempDir() + "/j85_ss.mat";
  write_state_space_mat(file, model_state_space_document(m, want));
  const StateSpace got = read_state_space_mat(file);
  expect_same(got, want, true, true);
  EXPECT_EQ(got.path_delay_s, want.path_delay_s);
  const Model back = parse_model(*state_space_document_if_mat(file), file);
  ASSERT_EQ(back.inputs.size(), m.inputs.size());
  for (size_t j = 0; j < m.inputs.size(); ++j) {
    EXPECT_EQ(back.inputs[j].units, m.inputs[j].units);
    EXPECT_EQ(back.inputs[j].full_scale, m.inputs[j].full_scale);
    ASSERT_EQ(bool(back.inputs[j].actuator), bool(m.inputs[j].actuator)) << m.inputs[j].name;
    if (m.inputs[j].actuator) {
      EXPECT_EQ(back.inputs[j].actuator->at(7.0), m.inputs[j].actuator->at(7.0));
    }
  }
  EXPECT_EQ(back.outputs[4].units, m.outputs[4].units);
  std::filesystem::remove(file);
}

// The file as MATLAB's and Octave's users take it: Octave loads it, builds `ss` with its names
// (the control package), and its frequency response with the delays is the model's.
TEST(StateSpaceMat, OctaveBuildsItsStateModelAndRespondsAsTheModel) {
  ASSERT_EQ(std::system("command -v octave-cli > /dev/null 2>&1 && octave-cli --eval "
                        "'pkg load control' > /dev/null 2>&1"),
            0)
      << "octave-cli with the control package: scripts/setup.sh --test installs them";
  const Model m = load_model(source_path("models/j85_95_sim.json"));
  const std::string dir = ::testing::TempDir() + "/octave_ss";
  std::filesystem::create_directories(dir);
  write_state_space_mat(dir + "/j85.mat", model_state_space_document(m, model_state_space(m)));
  // The model's responses: output, input (from 1), w rad/s, real, imaginary.
  {
    std::ofstream want(dir + "/want.txt");
    want.precision(17);
    for (double w = 1e-2; w < 1e3; w *= 1.5)
      for (size_t i = 0; i < m.outputs.size(); ++i)
        for (size_t j = 0; j < m.inputs.size(); ++j) {
          const auto h = m.position_to_output(int(i), int(j), w);
          want << i + 1 << ' ' << j + 1 << ' ' << w << ' ' << h.real() << ' ' << h.imag() << '\n';
        }
  }
  std::ofstream(dir + "/check.m")
      << "pkg load control\n"
         "load('j85.mat');\n"
         "sys = ss(A, B, C, D, 'StateName', StateName, 'InputName', InputName, "
         "'OutputName', OutputName);\n"
         "x = load('want.txt'); worst = 0;\n"
         "for k = 1:rows(x)\n"
         "  i = x(k,1); j = x(k,2); w = x(k,3); want = x(k,4) + 1i*x(k,5);\n"
         "  H = freqresp(sys(i, j), w);\n"
         "  H = H * exp(-1i*w*(InputDelay(j) + OutputDelay(i) + delay_s(i,j)));\n"
         "  if abs(want) > 0, worst = max(worst, abs(H - want) / abs(want));\n"
         "  else, worst = max(worst, abs(H)); end\n"
         "end\n"
         "printf('%.3e %d\\n', worst, numel(StateName));\n";
  const std::string cmd = "cd " + dir + " && octave-cli --no-gui -q check.m 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  char line[4096];
  std::string out;
  while (fgets(line, sizeof line, p)) out += line;
  ASSERT_EQ(pclose(p), 0) << out;
  double worst = NAN;
  int states = 0;
  ASSERT_EQ(std::sscanf(out.c_str(), "%lf %d", &worst, &states), 2) << out;
  EXPECT_LE(worst, 1e-9) << out;
  int order = 0;  // one state per pole of the paths (they share none)
  for (const ModelPath& path : m.paths) order += path.tf.den_order();
  EXPECT_EQ(states, order);
  std::filesystem::remove_all(dir);
}

TEST(StateSpaceMat, BadFilesAreRefusedNamingTheFileAndTheVariable) {
  const std::string dir = ::testing::TempDir();
  auto refused = [](const std::string& file, const std::string& what) {
    try {
      read_state_space_mat(file);
      ADD_FAILURE() << "accepted " << file;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(file));
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  // Not a .mat file at all.
  const std::string junk = dir + "/junk.mat";
  { std::ofstream(junk) << "not a mat file"; }
  refused(junk, "not a .mat file matio can read");
  // B as text.
  const std::string text_b = dir + "/text_b.mat";
  {
    mat_t* mat = Mat_CreateVer(text_b.c_str(), nullptr, MAT_FT_MAT5);
    double a[1] = {-1};
    size_t d1[2] = {1, 1}, d3[2] = {1, 3};
    char b[] = "abc";
    Mat_VarWrite(mat, Mat_VarCreate("A", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, d1, a, 0),
                 MAT_COMPRESSION_NONE);
    Mat_VarWrite(mat, Mat_VarCreate("B", MAT_C_CHAR, MAT_T_UINT8, 2, d3, b, 0),
                 MAT_COMPRESSION_NONE);
    Mat_VarWrite(mat, Mat_VarCreate("C", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, d1, a, 0),
                 MAT_COMPRESSION_NONE);
    Mat_Close(mat);
  }
  refused(text_b, "B: not a real matrix");
  // No model at all.
  const std::string none = dir + "/none.mat";
  {
    mat_t* mat = Mat_CreateVer(none.c_str(), nullptr, MAT_FT_MAT5);
    double x[1] = {1};
    size_t d1[2] = {1, 1};
    Mat_VarWrite(mat, Mat_VarCreate("x", MAT_C_DOUBLE, MAT_T_DOUBLE, 2, d1, x, 0),
                 MAT_COMPRESSION_NONE);
    Mat_Close(mat);
  }
  refused(none, "no state model");
}

}  // namespace
}  // namespace fralab
