#include "app/commands.hpp"
#include "app/selection_options.hpp"
#include "core/log.hpp"
#include "grid/phantom.hpp"
#include "io/nifti_writer.hpp"
#include "io/skull_phantom.hpp"

#include <CLI/CLI.hpp>

namespace vox::app {

void add_phantom_command(CLI::App& app)
{
    CLI::App* phantom = app.add_subcommand(
        "phantom", "Write a procedural test object (label 1; first voxel centred at the world origin)");
    phantom->require_subcommand(1);
    for (const auto shape : {grid::PhantomShape::beam, grid::PhantomShape::block, grid::PhantomShape::sphere,
                             grid::PhantomShape::cylinder, grid::PhantomShape::utube}) {
        auto spec = std::make_shared<grid::PhantomSpec>(grid::default_phantom(shape));
        auto output = std::make_shared<std::string>();
        auto size = std::make_shared<std::vector<double>>();
        CLI::App* cmd = phantom->add_subcommand(grid::phantom_shape_name(shape), "");
        cmd->add_option("-o,--output", *output, "Output .vdb file")->required();
        cmd->add_option("--voxel-mm", spec->voxel_mm, "Voxel edge, mm")->capture_default_str();
        switch (shape) {
        case grid::PhantomShape::beam:
        case grid::PhantomShape::block:
            cmd->description("Box of size_mm (x y z), voxels [0, n) on each axis");
            cmd->add_option("--size-mm", *size, "Extents x y z, mm (default " +
                                                    std::to_string(static_cast<int>(spec->size_mm.x())) + " " +
                                                    std::to_string(static_cast<int>(spec->size_mm.y())) + " " +
                                                    std::to_string(static_cast<int>(spec->size_mm.z())) + ")")
                ->expected(3);
            break;
        case grid::PhantomShape::sphere:
            cmd->description("Ball: voxels whose centre lies within radius of the centre of a 2r/h grid");
            cmd->add_option("--radius-mm", spec->radius_mm, "Radius, mm")->capture_default_str();
            break;
        case grid::PhantomShape::cylinder:
            cmd->description("Cylinder along x: length_mm long, disc of radius_mm across y and z");
            cmd->add_option("--radius-mm", spec->radius_mm, "Radius, mm")->capture_default_str();
            cmd->add_option("--length-mm", spec->length_mm, "Length along x, mm")->capture_default_str();
            break;
        case grid::PhantomShape::utube:
            cmd->description("U open upwards (z): two legs on a base; at level 3 with the defaults a coarse cell "
                             "holds both legs without the base (branched elements)");
            cmd->add_option("--leg-mm", spec->leg_mm, "Leg width (x) and base thickness (z), mm")->capture_default_str();
            cmd->add_option("--gap-mm", spec->gap_mm, "Gap between the legs (x), mm")->capture_default_str();
            cmd->add_option("--height-mm", spec->height_mm, "Total height (z), mm")->capture_default_str();
            cmd->add_option("--depth-mm", spec->depth_mm, "Extent along y, mm")->capture_default_str();
            break;
        }
        cmd->callback([spec, output, size] {
            require_vdb_extension(*output);
            if (size->size() == 3) spec->size_mm = {(*size)[0], (*size)[1], (*size)[2]};
            grid::LabelGrid labels = grid::make_phantom(*spec);
            labels.set_metadata("source", std::string("phantom ") + grid::phantom_shape_name(spec->shape));
            labels.save(*output);
            log::info("wrote {}: {} {} voxels of {} mm", *output, grid::phantom_shape_name(spec->shape),
                      labels.active_voxel_count(), spec->voxel_mm);
        });
    }

    auto skull = std::make_shared<io::SkullPhantomSpec>();
    auto skull_out = std::make_shared<std::string>();
    auto spacing = std::make_shared<std::vector<double>>();
    CLI::App* cmd = phantom->add_subcommand(
        "skull", "A head CT in Hounsfield units (.nii or .nii.gz): skull vault with orbits, brain, scalp, a separate "
                 "head holder and loose fragments; select bone with a threshold (226:3071)");
    cmd->add_option("-o,--output", *skull_out, "Output .nii.gz or .nii file")->required();
    cmd->add_option("--voxel-mm", *spacing, "Voxel spacing x y z, mm (default 0.9 0.9 1.5)")->expected(3);
    cmd->callback([skull, skull_out, spacing] {
        if (spacing->size() == 3) skull->voxel_mm = {(*spacing)[0], (*spacing)[1], (*spacing)[2]};
        const io::Volume v = io::make_skull_phantom(*skull);
        io::write_nifti(v, *skull_out);
        log::info("wrote {}: skull phantom, {} x {} x {} voxels of {} x {} x {} mm", *skull_out, v.dims[0], v.dims[1],
                  v.dims[2], skull->voxel_mm.x(), skull->voxel_mm.y(), skull->voxel_mm.z());
    });
}

} // namespace vox::app
