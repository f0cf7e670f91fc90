#include "io/vtu_writer.hpp"

#include "core/atomic_file.hpp"
#include "core/error.hpp"

#include <fstream>

namespace vox::io {

void write_vtu(const VtuMesh& mesh, const std::filesystem::path& path)
{
    const std::size_t corners = mesh.cell_type == VtuMesh::k_tetra ? 4 : 8;
    const std::size_t cells = mesh.cell_count();
    for (const auto& [name, values] : mesh.point_vectors)
        if (values.size() != mesh.points.size()) throw std::logic_error("vtu: point array " + name + " has the wrong size");
    for (const auto& [name, values] : mesh.cell_scalars)
        if (values.size() != cells) throw std::logic_error("vtu: cell array " + name + " has the wrong size");
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        std::ofstream out(tmp);
        out.precision(9);
        out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\">\n"
            << "<UnstructuredGrid>\n<Piece NumberOfPoints=\"" << mesh.points.size() << "\" NumberOfCells=\"" << cells << "\">\n"
            << "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
        for (const Eigen::Vector3d& p : mesh.points) out << p.x() << " " << p.y() << " " << p.z() << "\n";
        out << "</DataArray>\n</Points>\n<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
        for (std::size_t i = 0; i < mesh.connectivity.size(); ++i) out << mesh.connectivity[i] << ((i + 1) % corners == 0 ? "\n" : " ");
        out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
        for (std::size_t c = 1; c <= cells; ++c) out << c * corners << "\n";
        out << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
        for (std::size_t c = 0; c < cells; ++c) out << mesh.cell_type << "\n";
        out << "</DataArray>\n</Cells>\n<PointData>\n";
        for (const auto& [name, values] : mesh.point_vectors) {
            out << "<DataArray type=\"Float64\" Name=\"" << name << "\" NumberOfComponents=\"3\" format=\"ascii\">\n";
            for (const Eigen::Vector3d& v : values) out << v.x() << " " << v.y() << " " << v.z() << "\n";
            out << "</DataArray>\n";
        }
        out << "</PointData>\n<CellData>\n";
        for (const auto& [name, values] : mesh.cell_scalars) {
            out << "<DataArray type=\"Float64\" Name=\"" << name << "\" format=\"ascii\">\n";
            for (const double v : values) out << v << "\n";
            out << "</DataArray>\n";
        }
        out << "</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
        if (!out) throw file_error(path.string(), "cannot be written");
    });
}

void write_pvd(const std::vector<std::pair<double, std::string>>& frames, const std::filesystem::path& path)
{
    write_atomically(path, [&](const std::filesystem::path& tmp) {
        std::ofstream out(tmp);
        out.precision(9);
        out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\">\n<Collection>\n";
        for (const auto& [t, file] : frames) out << "<DataSet timestep=\"" << t << "\" part=\"0\" file=\"" << file << "\"/>\n";
        out << "</Collection>\n</VTKFile>\n";
        if (!out) throw file_error(path.string(), "cannot be written");
    });
}

} // namespace vox::io
