; Folds of message definitions: each section of a service or event, header to last field.

(section) @fold
