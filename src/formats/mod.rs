//! Files in and out, one file per format: each holds its parser (`parse_*`, from the file's
//! bytes or text: no file is read, the path only names it in messages), a thin reader of the
//! file (`read_*`), its writer and its element-type table. Every output is written atomically (a
//! temporary name, then a rename: [`write_atomic`]).
//!
//! | file | format |
//! |---|---|
//! | `outline`, `outline_csv`, `outline_text` | 2D outlines: the dispatch, long CSV tables (and 3D point sets), plain text |
//! | `csv_table` | CSV tables with columns by name |
//! | `surface`, `ply`, `stl`, `obj` | 3D surfaces: the dispatch and checks, PLY, STL, OBJ |
//! | `shape_file` | shapes out in the formats asked (VTP, VTK, PLY, STL) |
//! | `vtk_legacy` | legacy VTK: POLYDATA outlines and surfaces, UNSTRUCTURED_GRID meshes |
//! | `vtk_xml` | VTK XML: VTP shapes, VTU meshes |
//! | `fe_mesh` | FE meshes: the format by extension ([`MeshFormat`]) |
//! | `helpers` | what the readers and writers share: text, numbers, coordinates, mesh checks |
//! | `abaqus` | Abaqus/CalculiX `.inp` meshes and decks |
//! | `calculix_frd` | CalculiX's results (`.frd`): the nodal displacements of a solve |
//! | `gmsh`, `gmsh_binary`, `gmsh_parsed` | Gmsh `.msh`: ASCII and the mesh's assembly; binary files; what both fill |
//! | `febio` | FEBio `.feb` |
//! | `deck` | solver decks (`.inp`, `.feb`) copied per subject with its nodes |
//! | `landmarks` | landmark files (JSON, `.pts`, CSV) |
//! | `sets_file` | the sets file (TOML) |
//! | `load_case_file` | the load case file (TOML) |
//! | `atlas_file` | the atlas file (safetensors) |
//! | `image_file`, `image_data`, `nifti`, `nrrd`, `metaimage`, `dicom_series`, `dicom_lengths` | images (label maps, CT): the dispatch; what the readers share (decompression within the announced size); NIfTI-1/2, NRRD, MetaImage, DICOM series; a DICOM file's declared lengths checked before it is parsed |
//! | `input` | input files: regular files only, of bounded size |
//! | `atomic` | output folders and atomic writes |

pub mod abaqus;
pub mod atlas_file;
mod atomic;
pub mod calculix_frd;
pub mod csv_table;
mod deck;
mod dicom_lengths;
pub mod dicom_series;
pub mod fe_mesh;
pub mod febio;
pub mod gmsh;
mod gmsh_binary;
mod gmsh_parsed;
mod helpers;
mod image_data;
pub mod image_file;
pub mod input;
pub mod landmarks;
mod load_case_file;
pub mod metaimage;
pub mod nifti;
pub mod nrrd;
pub mod obj;
pub mod outline;
pub mod outline_csv;
pub mod outline_text;
pub mod ply;
mod recipe_file;
mod sets_file;
pub mod shape_file;
pub mod stl;
pub mod surface;
mod vtk_cells;
pub mod vtk_legacy;
pub mod vtk_xml;
mod vtk_xml_read;

pub use abaqus::{InpDeck, inp_step, parse_inp, read_inp};
pub use atlas_file::{ATLAS_FORMAT_VERSION, atlas_dimension};
pub(crate) use atomic::MAX_COUNT;
pub use atomic::{create_dir, lock_dir, write_atomic};
pub use calculix_frd::{parse_frd_displacements, read_frd_displacements};
pub use csv_table::CsvColumns;
pub use deck::{Deck, FebDeck};
pub use fe_mesh::{
    MeshFormat, check_fe_mesh, parse_fe_mesh_raw, read_fe_mesh, read_fe_mesh_raw, to_dimension,
    write_mesh, write_mesh_with_materials, write_model,
};
pub use gmsh::{parse_msh, read_msh};
pub use image_file::{ImageFile, ImageFormat, is_image_file, read_image};
pub(crate) use input::check_points;
pub use input::{DEFAULT_MAX_POINTS, max_points, read_input, read_input_text};
pub use outline::{
    outline_from_vtk, parse_outlines, parse_outlines_with, read_outlines, read_outlines_with,
};
pub use outline_csv::{
    csv_holds_3d_points, parse_long_csv, parse_long_csv_with, parse_point_sets_csv, read_long_csv,
    read_point_sets_csv,
};
pub use outline_text::{parse_text_outlines, read_text_outlines};
pub use ply::write_ply;
pub use shape_file::{ShapeFormat, write_shape};
pub use stl::write_stl;
pub use surface::{
    parse_surface, read_point_set, read_polydata, read_surface, surface_from_polydata,
};
pub use vtk_cells::VtkPolyData;
pub use vtk_legacy::{
    parse_vtk_outline, parse_vtk_polydata, parse_vtk_unstructured, read_vtk_outline,
    read_vtk_polydata, read_vtk_unstructured,
};
pub use vtk_xml::{
    parse_vtp, parse_vtu, read_vtp, read_vtu, write_vtp, write_vtp_with_point_data, write_vtu,
    write_vtu_with_point_data, write_vtu_with_quality,
};

#[cfg(test)]
mod fe_mesh_tests;
#[cfg(test)]
mod outline_tests;
#[cfg(test)]
mod round_trip_tests;
#[cfg(test)]
mod surface_tests;
#[cfg(test)]
mod vtk_xml_tests;
