//! The integration tests, in one binary: the library on the shared data, the command-line
//! tool as users run it, and the files it writes read back by other programs.

mod common;
mod raw_femurs;

mod aorta;
mod bad_input;
mod batch;
mod cli;
mod cut_bones;
mod ecosystem;
mod femur;
mod fuzz_regressions;
mod hands;
mod harness;
mod hostile;
mod hostile_inputs;
mod hostile_outputs;
mod html;
mod instances;
mod label_maps;
mod materials;
mod model_only;
mod posterior;
mod register;
mod repair;
mod solver;
mod spine_benchmark;
mod streamed;
mod vertebrae;
mod workflow;
