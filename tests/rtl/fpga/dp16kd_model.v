// A behavioural model of the ECP5 DP16KD block RAM, for simulating the Verilog that
// `rvsm fpga` builds (rvsm.rtl.fpga.ecp5_memory) with Icarus. yosys ships DP16KD as a
// black box only (share/lattice/cells_sim_ecp5.v), so this is a reading of the
// configuration the project uses, written for this test: both ports 18 bits wide (word
// address AD[13:4], AD[1:0] the byte enables of a write), port A writing, port B
// reading, WRITEMODE NORMAL, REGMODE NOREG or OUTREG, chip selects and resets tied to
// zero, the initial contents from INITVAL_00..3F (word k of INITVAL_j in bits
// [20k +: 18], address 16j + k: the layout of yosys' brams_map_16kd.v). A read of the
// address the other port writes at the same edge gives X (undefined on the device), so
// a design that lets such a read reach its outputs fails the comparison; it also prints
// a COLLISION line, so a read left ungated is seen even when its X never reaches an
// output (a discarded read of another bank's word). Any other
// configuration stops the simulation.
`timescale 1ns / 1ps
module DP16KD (
  input DIA17, DIA16, DIA15, DIA14, DIA13, DIA12, DIA11, DIA10, DIA9, DIA8, DIA7, DIA6, DIA5, DIA4, DIA3, DIA2, DIA1, DIA0,
  input ADA13, ADA12, ADA11, ADA10, ADA9, ADA8, ADA7, ADA6, ADA5, ADA4, ADA3, ADA2, ADA1, ADA0,
  input CEA, OCEA, CLKA, WEA, RSTA,
  input CSA2, CSA1, CSA0,
  output DOA17, DOA16, DOA15, DOA14, DOA13, DOA12, DOA11, DOA10, DOA9, DOA8, DOA7, DOA6, DOA5, DOA4, DOA3, DOA2, DOA1, DOA0,
  input DIB17, DIB16, DIB15, DIB14, DIB13, DIB12, DIB11, DIB10, DIB9, DIB8, DIB7, DIB6, DIB5, DIB4, DIB3, DIB2, DIB1, DIB0,
  input ADB13, ADB12, ADB11, ADB10, ADB9, ADB8, ADB7, ADB6, ADB5, ADB4, ADB3, ADB2, ADB1, ADB0,
  input CEB, OCEB, CLKB, WEB, RSTB,
  input CSB2, CSB1, CSB0,
  output DOB17, DOB16, DOB15, DOB14, DOB13, DOB12, DOB11, DOB10, DOB9, DOB8, DOB7, DOB6, DOB5, DOB4, DOB3, DOB2, DOB1, DOB0
);
  parameter DATA_WIDTH_A = 18;
  parameter DATA_WIDTH_B = 18;
  parameter REGMODE_A = "NOREG";
  parameter REGMODE_B = "NOREG";
  parameter RESETMODE = "SYNC";
  parameter ASYNC_RESET_RELEASE = "SYNC";
  parameter CSDECODE_A = "0b000";
  parameter CSDECODE_B = "0b000";
  parameter WRITEMODE_A = "NORMAL";
  parameter WRITEMODE_B = "NORMAL";
  parameter GSR = "DISABLED";
  parameter [319:0] INITVAL_00 = 320'h0;
  parameter [319:0] INITVAL_01 = 320'h0;
  parameter [319:0] INITVAL_02 = 320'h0;
  parameter [319:0] INITVAL_03 = 320'h0;
  parameter [319:0] INITVAL_04 = 320'h0;
  parameter [319:0] INITVAL_05 = 320'h0;
  parameter [319:0] INITVAL_06 = 320'h0;
  parameter [319:0] INITVAL_07 = 320'h0;
  parameter [319:0] INITVAL_08 = 320'h0;
  parameter [319:0] INITVAL_09 = 320'h0;
  parameter [319:0] INITVAL_0A = 320'h0;
  parameter [319:0] INITVAL_0B = 320'h0;
  parameter [319:0] INITVAL_0C = 320'h0;
  parameter [319:0] INITVAL_0D = 320'h0;
  parameter [319:0] INITVAL_0E = 320'h0;
  parameter [319:0] INITVAL_0F = 320'h0;
  parameter [319:0] INITVAL_10 = 320'h0;
  parameter [319:0] INITVAL_11 = 320'h0;
  parameter [319:0] INITVAL_12 = 320'h0;
  parameter [319:0] INITVAL_13 = 320'h0;
  parameter [319:0] INITVAL_14 = 320'h0;
  parameter [319:0] INITVAL_15 = 320'h0;
  parameter [319:0] INITVAL_16 = 320'h0;
  parameter [319:0] INITVAL_17 = 320'h0;
  parameter [319:0] INITVAL_18 = 320'h0;
  parameter [319:0] INITVAL_19 = 320'h0;
  parameter [319:0] INITVAL_1A = 320'h0;
  parameter [319:0] INITVAL_1B = 320'h0;
  parameter [319:0] INITVAL_1C = 320'h0;
  parameter [319:0] INITVAL_1D = 320'h0;
  parameter [319:0] INITVAL_1E = 320'h0;
  parameter [319:0] INITVAL_1F = 320'h0;
  parameter [319:0] INITVAL_20 = 320'h0;
  parameter [319:0] INITVAL_21 = 320'h0;
  parameter [319:0] INITVAL_22 = 320'h0;
  parameter [319:0] INITVAL_23 = 320'h0;
  parameter [319:0] INITVAL_24 = 320'h0;
  parameter [319:0] INITVAL_25 = 320'h0;
  parameter [319:0] INITVAL_26 = 320'h0;
  parameter [319:0] INITVAL_27 = 320'h0;
  parameter [319:0] INITVAL_28 = 320'h0;
  parameter [319:0] INITVAL_29 = 320'h0;
  parameter [319:0] INITVAL_2A = 320'h0;
  parameter [319:0] INITVAL_2B = 320'h0;
  parameter [319:0] INITVAL_2C = 320'h0;
  parameter [319:0] INITVAL_2D = 320'h0;
  parameter [319:0] INITVAL_2E = 320'h0;
  parameter [319:0] INITVAL_2F = 320'h0;
  parameter [319:0] INITVAL_30 = 320'h0;
  parameter [319:0] INITVAL_31 = 320'h0;
  parameter [319:0] INITVAL_32 = 320'h0;
  parameter [319:0] INITVAL_33 = 320'h0;
  parameter [319:0] INITVAL_34 = 320'h0;
  parameter [319:0] INITVAL_35 = 320'h0;
  parameter [319:0] INITVAL_36 = 320'h0;
  parameter [319:0] INITVAL_37 = 320'h0;
  parameter [319:0] INITVAL_38 = 320'h0;
  parameter [319:0] INITVAL_39 = 320'h0;
  parameter [319:0] INITVAL_3A = 320'h0;
  parameter [319:0] INITVAL_3B = 320'h0;
  parameter [319:0] INITVAL_3C = 320'h0;
  parameter [319:0] INITVAL_3D = 320'h0;
  parameter [319:0] INITVAL_3E = 320'h0;
  parameter [319:0] INITVAL_3F = 320'h0;

  wire [17:0] dia = {DIA17, DIA16, DIA15, DIA14, DIA13, DIA12, DIA11, DIA10, DIA9, DIA8, DIA7, DIA6, DIA5, DIA4, DIA3, DIA2, DIA1, DIA0};
  wire [13:0] ada = {ADA13, ADA12, ADA11, ADA10, ADA9, ADA8, ADA7, ADA6, ADA5, ADA4, ADA3, ADA2, ADA1, ADA0};
  wire [13:0] adb = {ADB13, ADB12, ADB11, ADB10, ADB9, ADB8, ADB7, ADB6, ADB5, ADB4, ADB3, ADB2, ADB1, ADB0};
  reg [17:0] mem [0:1023];
  reg [17:0] latch_b = 18'h0;
  reg [17:0] out_b = 18'h0;
  wire [17:0] dob = REGMODE_B == "OUTREG" ? out_b : latch_b;
  assign {DOB17, DOB16, DOB15, DOB14, DOB13, DOB12, DOB11, DOB10, DOB9, DOB8, DOB7, DOB6, DOB5, DOB4, DOB3, DOB2, DOB1, DOB0} = dob;
  assign {DOA17, DOA16, DOA15, DOA14, DOA13, DOA12, DOA11, DOA10, DOA9, DOA8, DOA7, DOA6, DOA5, DOA4, DOA3, DOA2, DOA1, DOA0} = 18'h0;

  task load(input [7:0] j, input [319:0] value);
    integer k;
    for (k = 0; k < 16; k = k + 1) mem[j * 16 + k] = value[k * 20 +: 18];
  endtask

  initial begin
    if (DATA_WIDTH_A != 18 || DATA_WIDTH_B != 18 || WRITEMODE_A != "NORMAL"
        || REGMODE_A != "NOREG" || (REGMODE_B != "NOREG" && REGMODE_B != "OUTREG")) begin
      $display("DP16KD model: unsupported configuration");
      $finish_and_return(2);
    end
    load(8'h00, INITVAL_00);
    load(8'h01, INITVAL_01);
    load(8'h02, INITVAL_02);
    load(8'h03, INITVAL_03);
    load(8'h04, INITVAL_04);
    load(8'h05, INITVAL_05);
    load(8'h06, INITVAL_06);
    load(8'h07, INITVAL_07);
    load(8'h08, INITVAL_08);
    load(8'h09, INITVAL_09);
    load(8'h0A, INITVAL_0A);
    load(8'h0B, INITVAL_0B);
    load(8'h0C, INITVAL_0C);
    load(8'h0D, INITVAL_0D);
    load(8'h0E, INITVAL_0E);
    load(8'h0F, INITVAL_0F);
    load(8'h10, INITVAL_10);
    load(8'h11, INITVAL_11);
    load(8'h12, INITVAL_12);
    load(8'h13, INITVAL_13);
    load(8'h14, INITVAL_14);
    load(8'h15, INITVAL_15);
    load(8'h16, INITVAL_16);
    load(8'h17, INITVAL_17);
    load(8'h18, INITVAL_18);
    load(8'h19, INITVAL_19);
    load(8'h1A, INITVAL_1A);
    load(8'h1B, INITVAL_1B);
    load(8'h1C, INITVAL_1C);
    load(8'h1D, INITVAL_1D);
    load(8'h1E, INITVAL_1E);
    load(8'h1F, INITVAL_1F);
    load(8'h20, INITVAL_20);
    load(8'h21, INITVAL_21);
    load(8'h22, INITVAL_22);
    load(8'h23, INITVAL_23);
    load(8'h24, INITVAL_24);
    load(8'h25, INITVAL_25);
    load(8'h26, INITVAL_26);
    load(8'h27, INITVAL_27);
    load(8'h28, INITVAL_28);
    load(8'h29, INITVAL_29);
    load(8'h2A, INITVAL_2A);
    load(8'h2B, INITVAL_2B);
    load(8'h2C, INITVAL_2C);
    load(8'h2D, INITVAL_2D);
    load(8'h2E, INITVAL_2E);
    load(8'h2F, INITVAL_2F);
    load(8'h30, INITVAL_30);
    load(8'h31, INITVAL_31);
    load(8'h32, INITVAL_32);
    load(8'h33, INITVAL_33);
    load(8'h34, INITVAL_34);
    load(8'h35, INITVAL_35);
    load(8'h36, INITVAL_36);
    load(8'h37, INITVAL_37);
    load(8'h38, INITVAL_38);
    load(8'h39, INITVAL_39);
    load(8'h3A, INITVAL_3A);
    load(8'h3B, INITVAL_3B);
    load(8'h3C, INITVAL_3C);
    load(8'h3D, INITVAL_3D);
    load(8'h3E, INITVAL_3E);
    load(8'h3F, INITVAL_3F);
  end

  always @(posedge CLKA) begin
    if (CEA && WEA && !CSA0 && !CSA1 && !CSA2 && !RSTA) begin
      if (ada[0]) mem[ada[13:4]][8:0] <= dia[8:0];
      if (ada[1]) mem[ada[13:4]][17:9] <= dia[17:9];
    end
  end

  always @(posedge CLKB) begin
    if (WEB || CSB0 || CSB1 || CSB2 || RSTB || RSTA) begin
      $display("DP16KD model: port B writes, chip selects and resets are not modelled");
      $finish_and_return(2);
    end
    if (CEB && CEA && WEA && ada[13:4] == adb[13:4])
      $display("DP16KD model: COLLISION (a read meets a write of its address) %m");
    if (CEB)
      latch_b <= (CEA && WEA && ada[13:4] == adb[13:4]) ? 18'bx : mem[adb[13:4]];
    if (OCEB) out_b <= latch_b;
  end
endmodule
