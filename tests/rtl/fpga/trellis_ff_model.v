// A behavioural model of the ECP5 TRELLIS_FF in the one configuration the ECP5 build
// instantiates (rvsm.rtl.fpga.ecp5_memory.kept_register): rising-edge clock, no clock
// enable (CEMUX "1") or CE high (CEMUX "CE"), set/reset input tied low, GSR disabled
// (0 at configuration, as REGSET "RESET" on the device): Q <= DI at every enabled edge.
// yosys' share/ecp5/cells_sim.v has the full model; this one keeps the Icarus bench
// self-contained. Any other configuration stops the simulation.
`timescale 1ns / 1ps
module TRELLIS_FF (input CLK, LSR, CE, DI, M, output reg Q = 1'b0);
  parameter GSR = "ENABLED";
  parameter [127:0] CEMUX = "1";
  parameter CLKMUX = "CLK";
  parameter LSRMUX = "LSR";
  parameter SRMODE = "LSR_OVER_CE";
  parameter REGSET = "RESET";
  parameter [127:0] LSRMODE = "LSR";
  initial begin
    if (GSR != "DISABLED" || (CEMUX != "1" && CEMUX != "CE") || CLKMUX != "CLK" || REGSET != "RESET") begin
      $display("TRELLIS_FF model: unsupported configuration");
      $finish;
    end
  end
  always @(posedge CLK) begin
    if (LSR !== 1'b0) begin
      $display("TRELLIS_FF model: LSR must be tied low");
      $finish;
    end
    if (CEMUX == "1" || CE === 1'b1) Q <= DI;
    else if (CE !== 1'b0) Q <= 1'bx;
  end
endmodule
