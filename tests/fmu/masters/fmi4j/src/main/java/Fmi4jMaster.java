import java.io.BufferedWriter;
import java.io.File;
import java.io.IOException;
import java.nio.charset.StandardCharsets;
import java.nio.file.Files;
import java.nio.file.Path;
import java.nio.file.Paths;
import java.util.ArrayList;
import java.util.LinkedHashMap;
import java.util.List;
import java.util.Map;

import no.ntnu.ihb.fmi4j.FmiStatus;
import no.ntnu.ihb.fmi4j.importer.fmi2.CoSimulationSlave;
import no.ntnu.ihb.fmi4j.importer.fmi2.Fmu;
import no.ntnu.ihb.fmi4j.modeldescription.variables.ModelVariables;

/**
 * A fixed-step FMI 2.0 co-simulation master over FMI4j's API, for tests/fmu/test_fmi4j_master.py.
 *
 * <pre>
 * Fmi4jMaster --fmu FMU --step H --steps N --outputs NAME,NAME,... --out CSV
 *             [--start NAME=VALUE]... [--inputs CSV] [--rollback-at K]
 * </pre>
 *
 * It makes the calls of {@code gimbal2axis.fmu.simulate} (gimbal2axis/fmu/fmu.py), in the same order and
 * with the same arguments: fmi2Instantiate (not visible, logging off); fmi2SetupExperiment with
 * no tolerance, start time 0 and no stop time; one fmi2SetReal of the start values;
 * fmi2EnterInitializationMode; fmi2ExitInitializationMode; then for k = 0 .. N-1: one fmi2SetReal
 * of row k of the inputs (if any), fmi2DoStep(k * H, H), one fmi2GetReal of the outputs;
 * fmi2Terminate; fmi2FreeInstance.
 *
 * With {@code --rollback-at K}: fmi2GetFMUstate at t = K * H (after step K-1, before row K's
 * inputs), on to step N-1 as usual, fmi2SetFMUstate, one fmi2GetReal, steps K .. N-1 again with the
 * same inputs and the same arguments, fmi2FreeFMUstate.
 *
 * Every double crosses the process boundary as a hexadecimal literal (Java's
 * {@link Double#toHexString} and {@link Double#parseDouble}, Python's float.hex and float.fromhex):
 * exact both ways by construction, with no decimal conversion to trust for a bit-for-bit comparison.
 * All input files hold such literals; --start and --step too.
 *
 * Output CSV: header {@code pass,step,<outputs>}; a row holds the outputs after step {@code step},
 * that is at t = (step + 1) * H. Pass 0 is the run, pass 1 the replay after the rollback; its first
 * row (step K-1) is read right after fmi2SetFMUstate.
 *
 * Exits non-zero, with the FMI call and FMI4j's last status on stderr, when a call does not return
 * fmi2OK. The FMU's log messages (FMI4j's native logger prints them) go to stdout.
 */
public final class Fmi4jMaster {

    private static final class Options {
        File fmu;
        double step;
        int steps;
        final Map<String, Double> start = new LinkedHashMap<>();
        String[] outputs;
        Path inputs;
        Path out;
        int rollbackAt = -1;
    }

    /** Input names and one row of values per step, all to be set before that step. */
    private static final class InputTable {
        final String[] names;
        final double[][] rows;

        InputTable(String[] names, double[][] rows) {
            this.names = names;
            this.rows = rows;
        }
    }

    public static void main(String[] args) throws IOException {
        Options options = parse(args);
        InputTable inputs = options.inputs == null ? null : readInputs(options.inputs, options.steps);
        List<String> rows = new ArrayList<>();

        Fmu fmu = Fmu.from(options.fmu);
        try {
            CoSimulationSlave slave = fmu.asCoSimulationFmu().newInstance("fmi4j", false, false);
            ModelVariables variables = slave.getModelDescription().getModelVariables();
            long[] startVrs = valueReferences(variables, options.start.keySet().toArray(new String[0]));
            double[] startValues = options.start.values().stream().mapToDouble(Double::doubleValue).toArray();
            long[] outputVrs = valueReferences(variables, options.outputs);
            long[] inputVrs = inputs == null ? null : valueReferences(variables, inputs.names);

            // start 0, stop 0 = start and tolerance 0: FMI4j then passes stopTimeDefined and
            // toleranceDefined false, as fmpy does for setupExperiment(startTime=0.0).
            check(slave.setupExperiment(0.0, 0.0, 0.0), slave, "fmi2SetupExperiment");
            if (startVrs.length > 0) check(slave.writeReal(startVrs, startValues), slave, "fmi2SetReal (start values)");
            check(slave.enterInitializationMode(), slave, "fmi2EnterInitializationMode");
            check(slave.exitInitializationMode(), slave, "fmi2ExitInitializationMode");

            long savedState = 0;
            for (int k = 0; k < options.steps; k++) {
                if (k == options.rollbackAt) {
                    savedState = slave.getFMUstate();
                    check(slave.getLastStatus(), slave, "fmi2GetFMUstate");
                }
                step(slave, k, options.step, inputs, inputVrs);
                rows.add(row(0, k, read(slave, outputVrs)));
            }
            if (options.rollbackAt >= 0) {
                check(slave.setFMUstate(savedState), slave, "fmi2SetFMUstate");
                rows.add(row(1, options.rollbackAt - 1, read(slave, outputVrs)));
                for (int k = options.rollbackAt; k < options.steps; k++) {
                    step(slave, k, options.step, inputs, inputVrs);
                    rows.add(row(1, k, read(slave, outputVrs)));
                }
                check(slave.freeFMUstate(savedState), slave, "fmi2FreeFMUstate");
            }
            check(slave.terminate(), slave, "fmi2Terminate");
            slave.close();
        } finally {
            fmu.close();
        }

        try (BufferedWriter writer = Files.newBufferedWriter(options.out, StandardCharsets.US_ASCII)) {
            writer.write("pass,step," + String.join(",", options.outputs));
            writer.newLine();
            for (String line : rows) {
                writer.write(line);
                writer.newLine();
            }
        }
    }

    private static void step(CoSimulationSlave slave, int k, double h, InputTable inputs, long[] inputVrs) {
        if (inputs != null) check(slave.writeReal(inputVrs, inputs.rows[k]), slave, "fmi2SetReal (inputs of step " + k + ")");
        // The same double as gimbal2axis.fmu.simulate's currentCommunicationPoint: k * step_size.
        double t = k * h;
        check(slave.doStep(t, h), slave, "fmi2DoStep(" + t + ", " + h + ")");
    }

    private static double[] read(CoSimulationSlave slave, long[] vrs) {
        double[] values = new double[vrs.length];
        check(slave.readReal(vrs, values), slave, "fmi2GetReal");
        return values;
    }

    private static String row(int pass, int step, double[] values) {
        StringBuilder line = new StringBuilder().append(pass).append(',').append(step);
        for (double value : values) line.append(',').append(Double.toHexString(value));
        return line.toString();
    }

    private static long[] valueReferences(ModelVariables variables, String[] names) {
        long[] vrs = new long[names.length];
        for (int i = 0; i < names.length; i++) {
            if (variables.getByNameOrNull(names[i]) == null)
                throw new IllegalArgumentException("the model description has no variable " + names[i]);
            // asRealVariable() throws for a variable that is not a Real.
            vrs[i] = variables.getByName(names[i]).asRealVariable().getValueReference();
        }
        return vrs;
    }

    private static void check(boolean ok, CoSimulationSlave slave, String call) {
        if (!ok) fail(call, slave.getLastStatus());
    }

    private static void check(FmiStatus status, CoSimulationSlave slave, String call) {
        if (status != FmiStatus.OK) fail(call, status);
    }

    private static void fail(String call, FmiStatus status) {
        System.err.println("Fmi4jMaster: " + call + " returned " + status);
        System.exit(2);
    }

    private static InputTable readInputs(Path file, int steps) throws IOException {
        List<String> lines = Files.readAllLines(file, StandardCharsets.US_ASCII);
        String[] names = lines.get(0).split(",");
        if (lines.size() - 1 != steps)
            throw new IllegalArgumentException(file + " has " + (lines.size() - 1) + " rows of inputs for " + steps + " steps");
        double[][] rows = new double[steps][];
        for (int k = 0; k < steps; k++) {
            String[] fields = lines.get(k + 1).split(",");
            if (fields.length != names.length)
                throw new IllegalArgumentException(file + ": row " + k + " has " + fields.length + " values for " + names.length + " names");
            rows[k] = new double[fields.length];
            for (int j = 0; j < fields.length; j++) rows[k][j] = Double.parseDouble(fields[j]);
        }
        return new InputTable(names, rows);
    }

    private static Options parse(String[] args) {
        Options options = new Options();
        for (int i = 0; i < args.length; i += 2) {
            if (i + 1 >= args.length) throw new IllegalArgumentException(args[i] + " needs a value");
            String value = args[i + 1];
            switch (args[i]) {
                case "--fmu": options.fmu = new File(value); break;
                case "--step": options.step = Double.parseDouble(value); break;
                case "--steps": options.steps = Integer.parseInt(value); break;
                case "--outputs": options.outputs = value.split(","); break;
                case "--inputs": options.inputs = Paths.get(value); break;
                case "--out": options.out = Paths.get(value); break;
                case "--rollback-at": options.rollbackAt = Integer.parseInt(value); break;
                case "--start": {
                    int equals = value.indexOf('=');
                    if (equals <= 0) throw new IllegalArgumentException("--start takes NAME=VALUE, not " + value);
                    options.start.put(value.substring(0, equals), Double.parseDouble(value.substring(equals + 1)));
                    break;
                }
                default: throw new IllegalArgumentException("unknown option " + args[i]);
            }
        }
        if (options.fmu == null || options.outputs == null || options.out == null || !(options.step > 0) || options.steps <= 0)
            throw new IllegalArgumentException("--fmu, --step > 0, --steps > 0, --outputs and --out are required");
        if (options.rollbackAt == 0 || options.rollbackAt >= options.steps)
            throw new IllegalArgumentException("--rollback-at K needs 0 < K < steps");
        return options;
    }
}
