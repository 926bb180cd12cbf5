% Writes the state-model test files (docs/formats.md §2b) with Octave: the same 4-state,
% 2-input, 3-output model as variables (-v7), as one struct (-v6) and in Dymola's dslin.mat
% layout (-v4: ABCD = [A B; C D], nx, xuyName). Run: octave --no-gui make_mat.m
A = [-3 0.5 0 0; 0.2 -1/3 0.1 0; 0 0.4 -20 8; 0 0 -8 -2];
B = [1 0; 0 0.5; 0 0; 0.3 1];
C = [1 0 0 0; 0 1 0.2 0; 0 0 0 1];
D = [0 0; 0 0; 0.01 0];
StateName = {'N'; 'T4'; 'P3'; 'Wf'};
InputName = {'fuel'; 'nozzle'};
OutputName = {'speed'; 'temp'; 'pres'};
InputDelay = [0.01; 0];
OutputDelay = [0; 0.002; 0];
save('-v7', 'ss_variables_v7.mat', 'A', 'B', 'C', 'D', 'StateName', 'InputName', 'OutputName', ...
     'InputDelay', 'OutputDelay');
sys = struct('A', A, 'B', B, 'C', C, 'D', D);
sys.StateName = StateName; sys.InputName = InputName; sys.OutputName = OutputName;
sys.InputDelay = InputDelay; sys.OutputDelay = OutputDelay;
save('-v6', 'ss_struct_v6.mat', 'sys');
ABCD = [A B; C D];
nx = 4;
xuyName = char([StateName; InputName; OutputName]);
save('-v4', 'dslin.mat', 'ABCD', 'nx', 'xuyName');
