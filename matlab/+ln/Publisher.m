% ln.Publisher — a publisher of one topic (docs/matlab.md): write(sample) packs a struct with
% the md's fields into the md's bytes and publishes it.  Made by ln.Client/publish; clearing
% it (or its client) unpublishes.  sample() and the rest come from ln.Port.
classdef Publisher < ln.Port
  methods
    function p = Publisher(client, topic, md, buffers)
      p = p@ln.Port(client, 'publish', topic, md, buffers);
    end

    function write(p, sample, timeout)
      % p.write(SAMPLE): SAMPLE is a struct with every field of the md (p.sample() gives one).
      if nargin < 3
        timeout = 1;
      end
      ln_mex('write', p.id, sample, timeout);
    end

    function n = subscribers(p)
      n = p.peers();
    end
  end
end
