//! Output writers (to any `std::io::Write`): particle CSV and legacy VTK polydata.
