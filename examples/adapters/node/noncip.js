#!/usr/bin/env node
// An independent implementation of the non-CIP Logix axis and its seven state
// instructions (MSO, MSF, MASD, MASR, MAFR, MDO, MDF), written from the vendor documents
// (the Motion State Instructions overview, the MDO page, the generic MOTION_INSTRUCTION
// execution table and error-code list) and the scan timing of docs/semantics.md, and
// served over the conformance protocol of docs/conformance.md (JSON Lines on stdin and
// stdout).  It does not read motionchart's specification.  What it leaves out it says in
// `hello`; where it reads the documents differently, known-failures.txt says why.
"use strict";

const readline = require("readline");

const PROTOCOL = "motionchart-conformance/1";
const STATES = { AxisReady: 0, DirectDriveControl: 1, ServoControl: 2, AxisFaulted: 3, Shutdown: 4 };
const INSTRUCTIONS = ["MSO", "MSF", "MASD", "MASR", "MAFR", "MDO", "MDF"];
// MOTION_INSTRUCTION bit numbers in FLAGS
const BITS = { EN: 31, DN: 29, ER: 28, PC: 27, IP: 26 };
// ERR codes (generic motion error table)
const ERR = { SERVO_ON: 4, DRIVE_ON: 6, AXIS_TYPE: 8, NOT_CONFIGURED: 11, MESSAGE: 12, RANGE: 13, FAULTED: 20, IN_MOTION: 22 };
const EX_SHUTDOWN = 12; // ERR 12 with EXERR 12: the axis is shut down (object mode conflict)
const ENABLE_DELAY_MS = 500; // MDO: drive enable to analog output

// Which axis data types each instruction accepts.
const TYPES = {
  MSO: ["AXIS_SERVO", "AXIS_SERVO_DRIVE", "AXIS_GENERIC"],
  MSF: ["AXIS_SERVO", "AXIS_SERVO_DRIVE", "AXIS_GENERIC"],
  MDO: ["AXIS_SERVO"],
  MDF: ["AXIS_SERVO"],
  MASD: ["AXIS_SERVO", "AXIS_SERVO_DRIVE", "AXIS_GENERIC", "AXIS_VIRTUAL"],
  MASR: ["AXIS_SERVO", "AXIS_SERVO_DRIVE", "AXIS_GENERIC", "AXIS_VIRTUAL"],
  MAFR: ["AXIS_SERVO", "AXIS_SERVO_DRIVE", "AXIS_GENERIC", "AXIS_VIRTUAL"],
};

class Axis {
  constructor(spec) {
    const v = spec.variables || {};
    this.name = spec.name;
    this.type = v.AxisType || spec.type;
    this.configured = v.Configured !== false;
    this.feedbackOnly = v.AxisConfiguration === "FeedbackOnly";
    this.faultAction = v.FaultAction || "DisableDrive";
    this.state = spec.state && spec.state in STATES ? spec.state : "AxisReady";
    // a set-up may start with a fault latched (ServoFault) and its cause present (FaultCondition)
    this.faultLatched = v.ServoFault === true || this.state === "AxisFaulted";
    this.faultCause = v.FaultCondition === true;
    this.moving = v.Moving === true;
    this.enableTimer = 0; // coarse updates until the MDO output is applied
    this.outputApplied = false;
  }

  observe() {
    const s = this.state;
    return {
      state: s,
      AxisState: STATES[s],
      ServoActionStatus: s === "ServoControl",
      DriveEnableStatus: s === "ServoControl" || s === "DirectDriveControl",
      ShutdownStatus: s === "Shutdown",
    };
  }

  enter(state) {
    this.state = state;
    if (state !== "DirectDriveControl") {
      this.enableTimer = 0;
      this.outputApplied = false;
    }
  }

  servoFault() {
    this.faultCause = true;
    this.faultLatched = true;
    if (this.state === "Shutdown") return;
    if (this.faultAction === "Shutdown") this.enter("Shutdown");
    else if (this.faultAction === "DisableDrive") this.enter("AxisFaulted");
    // Status Only / Stop Motion: the fault is latched, the state stays
  }
}

class Tag {
  constructor(call) {
    this.name = call.tag;
    this.mnemonic = call.instruction;
    this.axis = call.axis;
    this.operands = Object.assign({ DriveOutput: 0, DriveUnits: 0 }, call.operands || {});
    this.rung = false;
    this.EN = false; this.DN = false; this.ER = false; this.PC = false; this.IP = false;
    this.ERR = 0; this.EXERR = 0;
    this.pending = false;
  }

  observe() {
    let word = 0;
    for (const [m, bit] of Object.entries(BITS)) if (this[m]) word |= (1 << bit);
    return { EN: this.EN, DN: this.DN, ER: this.ER, PC: this.PC, IP: this.IP, ERR: this.ERR, EXERR: this.EXERR, FLAGS: word | 0 };
  }

  fail(err, exerr) {
    this.ERR = err; this.EXERR = exerr || 0; this.ER = true; this.DN = false; this.pending = false;
  }
}

class Controller {
  constructor(setup) {
    this.scanMs = setup.scan_ms;
    this.cuMs = setup.coarse_update_ms;
    this.perUpdate = Math.max(1, Math.floor(this.cuMs / this.scanMs));
    this.axes = new Map();
    for (const a of setup.axes) {
      if (a.family !== "AxisNonCIP") throw new Error(`axis family ${a.family} is not implemented`);
      this.axes.set(a.name, new Axis(a));
    }
    this.tags = [];
    for (const c of setup.program) {
      if (!INSTRUCTIONS.includes(c.instruction)) throw new Error(`instruction ${c.instruction} is not implemented`);
      if (!this.axes.has(c.axis)) throw new Error(`unknown axis ${c.axis}`);
      this.tags.push(new Tag(c));
    }
    this.index = 0;
    this.queue = [];
    this.held = [];
  }

  observe() {
    const out = {};
    for (const t of this.tags) out[t.name] = t.observe();
    for (const [name, a] of this.axes) out[name] = a.observe();
    return out;
  }

  // Checks made when the instruction executes in the scan (the controller knows them).
  scanCheck(t) {
    const a = this.axes.get(t.axis);
    if (!TYPES[t.mnemonic].includes(a.type)) return [ERR.AXIS_TYPE, 0];
    if (!a.configured) return [ERR.NOT_CONFIGURED, 0];
    if ((t.mnemonic === "MSO" || t.mnemonic === "MDO") && a.feedbackOnly) return [ERR.AXIS_TYPE, 0];
    if (t.mnemonic === "MDO") {
      const out = Number(t.operands.DriveOutput);
      const units = Number(t.operands.DriveUnits);
      const limit = units === 1 ? 100 : 10;
      if (!(Math.abs(out) <= limit)) return [ERR.RANGE, 2]; // EXERR: zero-based operand index
      if (units !== 0 && units !== 1) return [ERR.RANGE, 3];
    }
    return this.stateCheck(t, a, false);
  }

  // Checks that depend on the axis state; the Shutdown one is reported in the message answer.
  stateCheck(t, a, answering) {
    const s = a.state;
    if (answering && s === "Shutdown" && !["MASD", "MASR", "MAFR"].includes(t.mnemonic)) return [ERR.MESSAGE, EX_SHUTDOWN];
    switch (t.mnemonic) {
      case "MSO":
        if (s === "AxisFaulted") return [ERR.FAULTED, 0];
        if (s === "DirectDriveControl") return [ERR.DRIVE_ON, 0];
        if (a.moving && s !== "ServoControl") return [ERR.IN_MOTION, 0];
        return null;
      case "MDO":
        if (s === "ServoControl") return [ERR.SERVO_ON, 0];
        if (s === "DirectDriveControl") return [ERR.DRIVE_ON, 0];
        if (s === "AxisFaulted") return [ERR.FAULTED, 0];
        return null;
      case "MDF":
        if (s === "ServoControl") return [ERR.SERVO_ON, 0];
        return null;
      default:
        return null;
    }
  }

  execute(t) {
    t.DN = false; t.ER = false; t.PC = false; t.IP = false; t.ERR = 0; t.EXERR = 0;
    const bad = this.scanCheck(t);
    if (bad) { t.fail(bad[0], bad[1]); return; }
    t.pending = true;
    this.queue = this.queue.filter((n) => n !== t);
    this.queue.push(t);
  }

  // The axis carries out a request; true when the instruction is done at once.
  apply(t, a) {
    switch (t.mnemonic) {
      case "MSO": a.enter("ServoControl"); return true;
      case "MSF":
        if (a.state === "ServoControl" || a.state === "DirectDriveControl") a.enter("AxisReady");
        return true;
      case "MASD": a.enter("Shutdown"); a.moving = a.moving; return true;
      case "MASR":
        // faults are cleared; one whose cause persists is detected again at once
        a.faultLatched = false;
        if (a.state === "Shutdown" || a.state === "AxisFaulted") a.enter("AxisReady");
        if (a.faultCause) a.servoFault();
        return true;
      case "MAFR":
        a.faultLatched = a.faultCause;
        if (a.state === "AxisFaulted" && !a.faultLatched) a.enter("AxisReady");
        return true;
      case "MDO":
        a.enter("DirectDriveControl");
        a.enableTimer = Math.ceil(ENABLE_DELAY_MS / this.cuMs);
        a.outputApplied = false;
        return a.enableTimer === 0 ? (a.outputApplied = true) : false;
      case "MDF":
        if (a.state === "DirectDriveControl") a.enter("AxisReady");
        return true;
      default: return true;
    }
  }

  coarseUpdate() {
    const events = this.held;
    this.held = [];
    for (const [name, a] of this.axes) {
      // the enable delay of a running MDO counts down first
      if (a.state === "DirectDriveControl" && a.enableTimer > 0) {
        a.enableTimer -= 1;
        if (a.enableTimer === 0) a.outputApplied = true;
      }
      this.finishPending(a);
      for (const t of this.queue.filter((x) => x.axis === name)) {
        this.queue = this.queue.filter((x) => x !== t);
        if (!t.pending) continue;
        const bad = this.scanCheck(t) || this.stateCheck(t, a, true);
        if (bad) { t.fail(bad[0], bad[1]); continue; }
        if (this.apply(t, a)) { t.DN = true; t.pending = false; }
      }
      for (const e of events) {
        if (e.axis !== name) continue;
        if (e.event === "servo_fault") a.servoFault();
        else if (e.event === "fault_cleared") a.faultCause = false;
        else if (e.event === "motion_started") a.moving = true;
        else if (e.event === "motion_stopped") a.moving = false;
      }
      this.finishPending(a);
    }
  }

  // An MDO waiting for its enable delay: done when the output is applied, an error when
  // the axis left Direct Drive Control first.
  finishPending(a) {
    for (const t of this.tags) {
      if (!t.pending || this.axes.get(t.axis) !== a || this.queue.includes(t)) continue;
      if (a.state === "DirectDriveControl" && a.outputApplied) { t.DN = true; t.pending = false; }
      else if (a.state !== "DirectDriveControl") t.fail(ERR.MESSAGE, 1);
    }
  }

  scan(inputs) {
    for (const [tag, on] of Object.entries(inputs.rungs || {})) this.tag(tag).rung = on;
    for (const [tag, ops] of Object.entries(inputs.operands || {})) Object.assign(this.tag(tag).operands, ops);
    for (const e of inputs.events || []) this.held.push(e);
    if (inputs.prescan) {
      for (const t of this.tags) { t.EN = false; t.DN = false; t.ER = false; t.pending = false; }
      this.queue = [];
    } else {
      for (const t of this.tags) {
        if (t.rung) {
          if (!t.EN) { t.EN = true; this.execute(t); }
        } else if (t.DN || t.ER) {
          t.EN = false;
        }
      }
      if (this.index % this.perUpdate === 0) this.coarseUpdate();
    }
    this.index += 1;
    return this.observe();
  }

  tag(name) {
    const t = this.tags.find((x) => x.name === name);
    if (!t) throw new Error(`unknown tag ${name}`);
    return t;
  }
}

function hello() {
  return {
    type: "hello", protocol: PROTOCOL,
    implementation: { name: "noncip.js", version: "1" },
    supports: {
      axis_families: ["AxisNonCIP"],
      instructions: INSTRUCTIONS,
      observables: {
        tag: ["EN", "DN", "ER", "ERR", "EXERR", "FLAGS"],
        AxisNonCIP: ["state", "AxisState", "ServoActionStatus", "DriveEnableStatus", "ShutdownStatus"],
      },
      events: { AxisNonCIP: ["servo_fault", "fault_cleared", "motion_started", "motion_stopped"] },
      features: ["prescan"],
    },
  };
}

function main() {
  let controller = null;
  const rl = readline.createInterface({ input: process.stdin, terminal: false });
  const send = (msg) => process.stdout.write(JSON.stringify(msg) + "\n");
  rl.on("line", (line) => {
    if (!line.trim()) return;
    let msg;
    try { msg = JSON.parse(line); } catch (e) { send({ type: "error", message: `not JSON: ${e.message}` }); return; }
    try {
      switch (msg.type) {
        case "hello":
          if (msg.protocol !== PROTOCOL) send({ type: "error", message: `unsupported protocol ${msg.protocol}` });
          else send(hello());
          break;
        case "reset":
          controller = new Controller(msg.setup);
          send({ type: "ready", observations: controller.observe() });
          break;
        case "scan":
          if (!controller) throw new Error("scan before reset");
          send({ type: "observations", index: msg.index, observations: controller.scan(msg.inputs) });
          break;
        case "bye":
          send({ type: "bye" });
          rl.close();
          process.exit(0);
          break;
        default:
          send({ type: "error", message: `unknown message type ${msg.type}` });
      }
    } catch (e) {
      send({ type: "error", message: e.message });
    }
  });
}

main();
