#include "test_support.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>

namespace vox::test {

std::filesystem::path fresh_dir(const std::string& name)
{
    const std::filesystem::path d = std::filesystem::path(::testing::TempDir()) / name;
    std::filesystem::remove_all(d);
    std::filesystem::create_directories(d);
    return d;
}

ScratchDir::ScratchDir()
{
    const auto* test = ::testing::UnitTest::GetInstance()->current_test_info();
    std::string name = std::string("vox_") + test->test_suite_name() + "_" + test->name() + "_" +
                       std::to_string(::getpid());
    for (char& c : name)
        if (c == '/') c = '_'; // parameterised tests are named "Suite/Name/3"
    m_root = fresh_dir(name);
}

ScratchDir::~ScratchDir()
{
    std::error_code ec;
    std::filesystem::remove_all(m_root, ec);
}

std::string ScratchDir::path(const std::string& name) const { return (m_root / name).string(); }

std::string ScratchDir::write(const std::string& name, const std::string& bytes) const
{
    std::ofstream(path(name), std::ios::binary) << bytes;
    return path(name);
}

std::string error_of(const std::function<void()>& f)
{
    try {
        f();
    } catch (const InputError& e) {
        return e.what();
    }
    ADD_FAILURE() << "no InputError thrown";
    return {};
}

void expect_refused(const std::function<void()>& f, const std::string& file, const std::string& problem)
{
    const std::string message = error_of(f);
    EXPECT_EQ(message.rfind(file, 0), 0u) << "message does not start with the file: " << message;
    EXPECT_NE(message.find(problem), std::string::npos) << "message lacks '" << problem << "': " << message;
}

std::string quote(const std::string& s)
{
    std::string out = "'";
    for (const char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

int run_python(const std::string& script, const std::vector<std::string>& args, const std::string& output)
{
    std::string command = "/usr/bin/python3 " + quote(script);
    for (const std::string& a : args) command += " " + quote(a);
    if (!output.empty()) command += " > " + quote(output);
    const int status = std::system(command.c_str());
    if (status != 0) ADD_FAILURE() << command << " exited with status " << status;
    return status;
}

} // namespace vox::test
