% bench_octave(N, SECONDS) — the MATLAB/Octave client's cost per call (bench_octave.py runs
% it against a private manager): a plain Octave function call (the baseline), write + read
% of a 64-byte sample (lnmatlab/sample64) per call, and the rate a 1 kHz loop achieves with
% write + read + pause.  Prints one JSON object.
function bench_octave(n, seconds)
  c = ln.Client('bench_octave');
  p = c.publish('bench.m64', 'lnmatlab/sample64');
  s = c.subscribe('bench.m64', 'lnmatlab/sample64');
  m = p.sample();
  m.values = 1:8;
  f = @(x) x;
  t0 = tic;
  for i = 1:n
    m = identity(m);
  end
  baseline = toc(t0) / n;
  t0 = tic;
  for i = 1:n
    m = f(m);
  end
  anonymous = toc(t0) / n;
  t0 = tic;
  for i = 1:n
    p.write(m);
    r = s.read(0);
  end
  both = toc(t0) / n;
  t0 = tic;
  for i = 1:n
    p.write(m);
  end
  write_only = toc(t0) / n;
  t0 = tic;
  for i = 1:n
    r = s.read(0);
  end
  read_only = toc(t0) / n;
  % a 1 kHz loop: write + read, then sleep until the next period (absolute deadlines)
  period = 1e-3;
  cycles = 0;
  t0 = tic;
  next = period;
  while toc(t0) < seconds
    p.write(m);
    r = s.read(0);
    cycles = cycles + 1;
    left = next - toc(t0);
    if left > 0
      pause(left);
    end
    next = next + period;
  end
  rate = cycles / toc(t0);
  fprintf('%s\n', jsonencode(struct('baseline_us', baseline * 1e6, 'anonymous_us', ...
          anonymous * 1e6, 'write_read_us', both * 1e6, 'write_us', write_only * 1e6, ...
          'read_us', read_only * 1e6, 'loop_hz', rate, 'loop_target_hz', 1 / period, ...
          'calls', n, 'loop_seconds', seconds)));
end

function x = identity(x)
end
