% The field's reference numbers for limpid's real-ankle test (issue 78).
%
% Runs the REKLAB NLID toolbox's parallel-cascade identification,
% PC_stiffnessID (reklab/reklab_public, stiffnessID/), unmodified, on the
% five real ankle recordings of ../shared/real/reklab_ankle, with its
% nonlinear reflex ('sls': Hammerstein, Tchebyshev polynomial of order up to
% 8 by separable least squares) and with its rectifier ('rect'). K is the
% intrinsic IRF's DC gain (sum of the IRF times its lag step), how the
% toolbox's IRF gives stiffness. limpid's torque is applied to the ankle
% (tau1 = -tq1), so the sign of K is flipped when the numbers are kept.
%
% The toolbox is not shipped with limpid. To re-run (Debian):
%   apt-get install octave octave-signal octave-control octave-statistics
%   (nlid_tools, utility_tools and stiffnessID from reklab_public on the path)
%   octave --no-gui -q scripts/nlid-reference.m
% Made on 2026-12-07 with Octave 7.3 (Debian 12); twice, identical output.
pkg load signal
pkg load control
pkg load statistics
data = getenv('LIMPID_REAL_DATA');
names = {'df','pf','df2','df3','pf2'};
methods = {'sls','rect'};
for i = 1:numel(names)
  M = dlmread(fullfile(data, 'reklab_ankle', [names{i} '.csv']), ',', 1, 0);
  z = nldat([M(:,2) -M(:,3)], 'domainIncr', 0.001);
  for m = 1:numel(methods)
    [hI, mR, nlm, VAFT] = PC_stiffnessID(z, 'reflex_id_method', methods{m});
    K = sum(double(hI)) * get(hI, 'domainIncr');
    printf('%s %s VAF %.3f K %.3f\n', names{i}, methods{m}, double(VAFT), -K);
  end
end
