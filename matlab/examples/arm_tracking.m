% arm_tracking — the demo robot (examples/robot/robot.lnc) from MATLAB or GNU Octave: follows
% arm.state and the controller's arm.reference for DURATION s (default 5), switches the gains
% through the service arm.set_gains halfway, and plots the tracking error (rad, per cycle)
% when a figure can be shown; without a display it prints the figures only.
%   addpath build/release/matlab; addpath matlab/examples
%   setenv('LN_MANAGER', ':54414'); e = arm_tracking();
function result = arm_tracking(duration)
  if nargin < 1
    duration = 5;
  end
  c = ln.Client('arm_tracking');
  state = c.subscribe('arm.state', 'robot/joint_state', 64);
  reference = c.subscribe('arm.reference', 'robot/joint_state', 64);
  gains = c.service('arm.set_gains', 'robot/set_gains');

  cycles = zeros(1, 256); positions = zeros(256, 7);  % the newest states, by cycle
  t = []; err = [];
  switched = false;
  start = tic;
  while toc(start) < duration
    while true  % every state sample that came
      s = state.read(0);
      if isempty(s), break; end
      slot = mod(double(s.cycle), 256) + 1;
      cycles(slot) = double(s.cycle);
      positions(slot, :) = s.position;
    end
    r = reference.read(0.1);  % the controller's reference of the cycle of a state
    if ~isempty(r)
      slot = mod(double(r.cycle), 256) + 1;
      if cycles(slot) == double(r.cycle)
        t(end + 1) = toc(start);
        err(end + 1) = norm(r.position - positions(slot, :));
      end
    end
    if ~switched && toc(start) > duration / 2
      request = struct('kp', [300 300 200 150 80 50 25], 'kd', [25 25 16 12 6 4 2], ...
                       'profile_name', 'matlab-stiff');
      answer = gains.call(request, 2);
      fprintf('arm.set_gains: ok %d %s\n', answer.ok, answer.message);
      switched = true;
    end
  end
  result = struct('time', t, 'error', err, 'rms', sqrt(mean(err .^ 2)), 'samples', numel(err));
  fprintf('%d samples, rms tracking error %.3g rad\n', result.samples, result.rms);
  if can_plot()
    figure(); plot(t, err); xlabel('time (s)'); ylabel('tracking error (rad)');
    title('arm tracking error; gains switched halfway');
  end
end

function ok = can_plot()
  % A figure needs a display (or MATLAB's desktop) and a graphics toolkit.
  if exist('OCTAVE_VERSION', 'builtin')
    ok = ~isempty(getenv('DISPLAY')) && ~isempty(available_graphics_toolkits());
  else
    ok = usejava('desktop');
  end
end
