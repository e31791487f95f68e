pbppo-blob-signature 1
algorithm: ed25519
key: 8254c329a92850f6d539dd376f4816ee2764517da5e0235514af433164480d7a
blob-sha256: fa2c8cc4f28176bbeed4b736df569a34c79cd3723e9ec42f9674b4d46ac6b8b8
blob-bytes: 68025
policy: io_layout 0x45b7f39b788bf22a, 68025 bytes, pbppo-rt 0.1.0, git 1a2b3c4d5e6f, env quadruped-walk, seed 1, 6000000 steps
signature: 2c1ee68372215b1ce064426b5cdbd4ef2581ace0dd3b21fa2be27f364827242e83f68b68be03f5b3e24be5d1b4315f98a0a96d19713fb3a19dc455fb6adc3431
