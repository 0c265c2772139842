//! fmi_rs_host FMU OUT.csv me|cs STOP OUTPUT_INTERVAL EULER_STEP [NAME=VALUE ...]
//! fmi_rs_host validate MODEL_DESCRIPTION.xml
//!
//! Simulates an FMI 3.0 FMU with fmi-rs from time 0 to STOP, recording every output variable at each
//! OUTPUT_INTERVAL into OUT.csv. `me`: Model Exchange with fmi-rs' forward Euler of step EULER_STEP
//! (its own event handling); `cs`: Co-Simulation, one doStep per output interval, with Event Mode and
//! early return allowed. NAME=VALUE pairs are start values. `validate`: fmi-rs' own checks of an FMI
//! 2.0 or 3.0 model description, one problem a line on stdout. Exit status 0 on success (no problem),
//! 1 with the reason on stderr otherwise.
use std::{env, process::ExitCode, sync::Arc};

use fmi_rs::fmi3::{builder::FMU3Builder, LibraryKind};
use fmi_rs::model_description::fmi3::{Causality, ModelDescription};
use fmi_rs::model_description::{fmi2, peek_fmi_major_version, FMIMajorVersion};
use fmi_rs::sim::fmi3::{csv::write_csv, recorder::Recorder, SimulationSettings, Trajectories};
use fmi_rs::sim::solver::ForwardEulerFactory;

fn validate(path: &str) -> Result<(), String> {
    let path = std::path::Path::new(path);
    let problems = match peek_fmi_major_version(path).map_err(|e| format!("{}: {e}", path.display()))? {
        FMIMajorVersion::V2 => fmi2::ModelDescription::from_path(path).map_err(|e| format!("{e}"))?.validate(),
        FMIMajorVersion::V3 => ModelDescription::from_path(path).map_err(|e| format!("{e}"))?.validate(),
    };
    for problem in &problems {
        println!("{}", problem.message);
    }
    if problems.is_empty() { Ok(()) } else { Err(format!("{} problem(s)", problems.len())) }
}

fn run(args: &[String]) -> Result<(), String> {
    if args.len() == 3 && args[1] == "validate" {
        return validate(&args[2]);
    }
    if args.len() < 7 {
        return Err("usage: fmi_rs_host FMU OUT.csv me|cs STOP OUTPUT_INTERVAL EULER_STEP [NAME=VALUE ...]".into());
    }
    let number = |text: &str| text.parse::<f64>().map_err(|e| format!("{text}: {e}"));
    let (stop_time, output_interval, euler_step) = (number(&args[4])?, number(&args[5])?, number(&args[6])?);
    let builder = FMU3Builder::new(&args[1]).map_err(|e| format!("cannot open {}: {e}", args[1]))?;
    let model_description = Arc::new(
        ModelDescription::from_path(&builder.unzipdir.path().join("modelDescription.xml"))
            .map_err(|e| format!("cannot read the model description: {e}"))?,
    );
    let start_values = args[7..]
        .iter()
        .map(|pair| {
            let (name, value) = pair.split_once('=').ok_or(format!("{pair}: expected NAME=VALUE"))?;
            Ok((name.to_string(), value.to_string()))
        })
        .collect::<Result<Vec<_>, String>>()?;
    let settings = SimulationSettings {
        unzipdir: builder.unzipdir.path().to_path_buf(),
        model_description: model_description.clone(),
        library_kind: LibraryKind::Native,
        enable_dae: false,
        start_time: 0.0,
        stop_time,
        visible: false,
        logging_on: false,
        set_stop_time: true,
        output_interval,
        log_time_scale: false,
        tolerance: 0.0,
        set_tolerance: false,
        start_values,
        log_fmi_calls: false,
        intermediate_update: false,
        input_file: None,
        early_return_allowed: true,
        event_mode_used: true,
        log_file: None,
        initial_fmu_state_file: None,
        final_fmu_state_file: None,
    };
    let outputs = model_description
        .modelVariables
        .iter()
        .enumerate()
        .filter(|(_, v)| v.causality == Causality::Output)
        .map(|(i, _)| i)
        .collect();
    let recorder = Arc::new(Recorder::new(Trajectories::new(model_description.clone(), outputs)));
    let result = match args[3].as_str() {
        "me" => fmi_rs::sim::fmi3::me::simulate(
            &settings,
            &ForwardEulerFactory { fixed_step_size: euler_step },
            None,
            recorder.clone(),
        ),
        "cs" => fmi_rs::sim::fmi3::cs::simulate(&settings, None, recorder.clone()),
        other => return Err(format!("{other}: expected me or cs")),
    };
    result.map_err(|e| format!("simulation failed: {e}"))?;
    let trajectories = Arc::try_unwrap(recorder).map_err(|_| "the recorder is still shared".to_string())?;
    write_csv(&trajectories.into_trajectories(), &args[2]).map_err(|e| format!("cannot write {}: {e}", args[2]))
}

fn main() -> ExitCode {
    let args: Vec<String> = env::args().collect();
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("fmi_rs_host: {message}");
            ExitCode::FAILURE
        }
    }
}
