% ln.Subscriber — a subscriber of one topic (docs/matlab.md): read(timeout) gives the next
% sample as a struct with the md's fields, [] when none came in time.  Made by
% ln.Client/subscribe; clearing it (or its client) unsubscribes.  sample() and the rest come
% from ln.Port.
classdef Subscriber < ln.Port
  methods
    function s = Subscriber(client, topic, md, buffers)
      s = s@ln.Port(client, 'subscribe', topic, md, buffers);
    end

    function [sample, info] = read(s, timeout)
      % [SAMPLE, INFO] = s.read(TIMEOUT): waits up to TIMEOUT s (default 1; 0 does not wait,
      % a negative one waits forever) and returns [] if no sample came.  INFO has seq,
      % timestamp (s since the epoch) and overruns.
      if nargin < 2
        timeout = 1;
      end
      [sample, info] = ln_mex('read', s.id, timeout);
    end

    function n = publishers(s)
      n = s.peers();
    end
  end
end
