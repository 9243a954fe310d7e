"""cocotb testbenches that drive the generated Verilog with the fixed twin's stimulus."""
